"""Type stubs of mcrt (the functions are implemented in Rust, mcrt._mcrt)."""

import os
from typing import Callable, Dict, Literal, Mapping, Optional, Sequence, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
FloatArray = npt.NDArray[np.float32]
ArrayLike = npt.ArrayLike
Progress = Union[None, bool, Callable[[int, Optional[int]], object]]
Integrator = Literal["path", "direct", "photon", "sppm"]
Sampler = Literal["independent", "sobol"]
AovName = Literal["albedo", "normal", "depth", "variance", "spp"]

class Error(Exception):
    """Any error of mcrt; its message is the one the `mcrt` command prints."""

class SceneError(Error):
    """A bad scene file: `file:line:column: message`."""

    path: str
    line: Optional[int]
    column: Optional[int]

class UsageError(Error):
    """A bad argument: a setting out of range, an unknown name, a wrong combination."""

class ImageError(Error):
    """An image that cannot be read or written."""

class RenderError(Error):
    """A failure while rendering."""

class Scene:
    """A scene read from a file and built, ready to render any number of times."""

    @property
    def path(self) -> str: ...
    @property
    def cameras(self) -> list[str]: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def width(self) -> Optional[int]: ...
    @property
    def height(self) -> Optional[int]: ...
    @property
    def spp(self) -> Optional[int]: ...

class Metrics:
    """Error metrics of an image against a reference (as `mcrt compare`)."""

    mse: float
    rmse: float
    rel_mse: float
    psnr: float
    max_abs: float

def load(path: PathLike, *, lenient: bool = False, **params: object) -> Scene:
    """Reads a `.toml` or Mitsuba `.xml` scene and builds it; `params` are XML `-D` values."""

@overload
def render(
    scene: Union[Scene, PathLike],
    *,
    spp: Optional[int] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    seed: Optional[int] = None,
    integrator: Optional[Integrator] = None,
    time: Union[None, float, str] = None,
    threads: Optional[int] = None,
    sampler: Optional[Sampler] = None,
    max_depth: Optional[int] = None,
    shadow_rays: Optional[int] = None,
    camera: Optional[str] = None,
    target_noise: Optional[float] = None,
    adaptive: bool = False,
    aovs: None = None,
    progress: Progress = None,
    backend: Optional[str] = None,
    photons: Optional[int] = None,
    caustic_photons: Optional[int] = None,
    gather_photons: Optional[int] = None,
    final_gather: Optional[int] = None,
    iterations: Optional[int] = None,
    photons_per_iteration: Optional[int] = None,
    initial_radius: Optional[float] = None,
) -> FloatArray:
    """Renders; returns float32 linear RGB of shape (height, width, 3)."""

@overload
def render(
    scene: Union[Scene, PathLike],
    *,
    spp: Optional[int] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    seed: Optional[int] = None,
    integrator: Optional[Integrator] = None,
    time: Union[None, float, str] = None,
    threads: Optional[int] = None,
    sampler: Optional[Sampler] = None,
    max_depth: Optional[int] = None,
    shadow_rays: Optional[int] = None,
    camera: Optional[str] = None,
    target_noise: Optional[float] = None,
    adaptive: bool = False,
    aovs: Union[str, Sequence[AovName]],
    progress: Progress = None,
    backend: Optional[str] = None,
    photons: Optional[int] = None,
    caustic_photons: Optional[int] = None,
    gather_photons: Optional[int] = None,
    final_gather: Optional[int] = None,
    iterations: Optional[int] = None,
    photons_per_iteration: Optional[int] = None,
    initial_radius: Optional[float] = None,
) -> Dict[str, FloatArray]:
    """Renders with AOVs; returns {"image": ..., "albedo": ..., ...}."""

def write(
    path: PathLike,
    image: ArrayLike,
    *,
    exposure: float = 0.0,
    tonemap: Literal["clamp", "reinhard", "aces"] = "clamp",
    half: bool = False,
    aovs: Optional[Mapping[str, ArrayLike]] = None,
) -> None:
    """Writes an (H, W, 3) image as `.exr` or `.png` (atomically), with optional AOV layers."""

def read(path: PathLike) -> FloatArray:
    """Reads an `.exr` or `.png` image as float32 linear RGB of shape (H, W, 3)."""

def compare(
    a: Union[PathLike, ArrayLike],
    b: Union[PathLike, ArrayLike],
    *,
    diff: Optional[PathLike] = None,
    diff_range: Optional[float] = None,
) -> Metrics:
    """RMSE, relMSE and PSNR of `a` against the reference `b` (as `mcrt compare`)."""
