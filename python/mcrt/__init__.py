"""mcrt: a physically based Monte Carlo ray tracer, from Python.

    import mcrt
    scene = mcrt.load("scenes/cornell-box.toml")
    image = mcrt.render(scene, spp=64, width=256, height=256, seed=1)  # float32 (H, W, 3)
    mcrt.write("cornell.png", image)

`render` returns the same bits as `mcrt render` writes to an EXR for the same settings and seed.
Errors are `mcrt.Error` exceptions (`SceneError`, `UsageError`, `ImageError`, `RenderError`)
with the message the command line prints (`file:line:column: message` for scene files).
"""

from ._mcrt import (
    Error,
    ImageError,
    Metrics,
    RenderError,
    Scene,
    SceneError,
    UsageError,
    __version__,
    compare,
    load,
    read,
    render,
    write,
)

__all__ = [
    "Error",
    "ImageError",
    "Metrics",
    "RenderError",
    "Scene",
    "SceneError",
    "UsageError",
    "__version__",
    "compare",
    "load",
    "read",
    "render",
    "write",
]
