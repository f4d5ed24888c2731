"""Tests of the Python module against the `mcrt` command: the same scene, settings and seed give
the same bits, the same error messages, the same files.

They need the module installed (`pip install .` at the repository root) and the release binary
(`cargo build --release`), or the binary named by the environment variable MCRT_BIN.
"""

import os
import pathlib
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import mcrt

ROOT = pathlib.Path(__file__).resolve().parents[2]
CORNELL = ROOT / "scenes" / "cornell-box.toml"
LIGHTS_XML = ROOT / "tests" / "data" / "mitsuba" / "features" / "lights.xml"
ALL_AOVS = "albedo,normal,depth,variance,spp"


def mcrt_bin():
    exe = pathlib.Path(os.environ.get("MCRT_BIN", ROOT / "target" / "release" / "mcrt"))
    assert exe.is_file(), f"{exe} is missing: build it with `cargo build --release`"
    return str(exe)


def cli(*args, ok=True):
    """Runs the mcrt command; returns (exit status, stdout, stderr)."""
    p = subprocess.run(
        [mcrt_bin(), *map(str, args)], capture_output=True, text=True, cwd=ROOT, timeout=600
    )
    if ok:
        assert p.returncode == 0, p.stderr
    return p.returncode, p.stdout, p.stderr


def cli_error(*args):
    """The message of a failing mcrt command (its `error: ` line, without the prefix)."""
    code, _, err = cli(*args, ok=False)
    assert code == 2, err
    line = [l for l in err.splitlines() if l.startswith("error: ")][-1]
    return line[len("error: ") :]


def test_render_equals_cli_exr_bit_for_bit(tmp_path):
    """The issue's proof: the array is the CLI's EXR, bit for bit."""
    img = mcrt.render("scenes/cornell-box.toml", spp=4, width=64, height=64, seed=3)
    out = tmp_path / "x.exr"
    cli("render", "scenes/cornell-box.toml", "--spp", 4, "--width", 64, "--height", 64,
        "--seed", 3, "-o", out, "--quiet")
    ref = mcrt.read(out)
    assert isinstance(img, np.ndarray)
    assert img.dtype == np.float32 and img.shape == (64, 64, 3)
    assert ref.dtype == np.float32 and ref.shape == (64, 64, 3)
    assert img.mean() > 0.01, "a black image would match trivially"
    assert np.array_equal(img.view(np.uint32), ref.view(np.uint32))
    # The seed is honoured: another seed gives another image.
    other = mcrt.render(CORNELL, spp=4, width=64, height=64, seed=4)
    assert not np.array_equal(img, other)


@pytest.mark.parametrize(
    "kwargs, flags",
    [
        (dict(integrator="direct", sampler="sobol"), ["--integrator", "direct", "--sampler", "sobol"]),
        (dict(max_depth=2, shadow_rays=2, threads=1), ["--max-depth", 2, "--shadow-rays", 2, "--threads", 1]),
        (dict(max_depth=-1, spp=3), ["--max-depth", -1, "--spp", 3]),
        (dict(integrator="photon", spp=1), ["--integrator", "photon", "--spp", 1]),
        (dict(integrator="photon", photons=3000, caustic_photons=2000, final_gather=2),
         ["--integrator", "photon", "--photons", 3000, "--caustic-photons", 2000,
          "--final-gather", 2]),
        (dict(integrator="sppm", iterations=3, photons_per_iteration=2000),
         ["--integrator", "sppm", "--iterations", 3, "--photons-per-iteration", 2000]),
        (dict(backend="scalar"), ["--backend", "scalar"]),
    ],
)
def test_settings_equal_cli_flags(tmp_path, kwargs, flags):
    """Each keyword means what the command's flag of the same name means."""
    scene = mcrt.load(CORNELL)
    base = dict(spp=2, width=24, height=16, seed=7)
    base.update(kwargs)
    img = mcrt.render(scene, **base)
    out = tmp_path / "x.exr"
    args = ["render", CORNELL, "--width", 24, "--height", 16, "--seed", 7, "-o", out, "-q"]
    if "spp" not in kwargs:
        args += ["--spp", 2]
    cli(*args, *flags)
    assert img.shape == (16, 24, 3)
    assert np.array_equal(img, mcrt.read(out))


def test_xml_params_are_defines(tmp_path):
    """load(path, name=value) is the command's -D name=value."""
    one = mcrt.render(mcrt.load(LIGHTS_XML, spp=1), width=32, height=24, seed=1)
    out = tmp_path / "x.exr"
    cli("render", LIGHTS_XML, "-D", "spp=1", "--width", 32, "--height", 24, "--seed", 1,
        "-o", out, "-q")
    assert np.array_equal(one, mcrt.read(out))
    two = mcrt.render(mcrt.load(LIGHTS_XML, spp=2), width=32, height=24, seed=1)
    assert not np.array_equal(one, two)


def test_aovs_are_the_cli_layers(tmp_path):
    """The AOV dict holds the layers `--aov` writes: writing it gives the CLI's file, byte for
    byte."""
    d = mcrt.render(CORNELL, spp=4, width=32, height=32, seed=3, aovs=ALL_AOVS.split(","))
    assert set(d) == {"image", "albedo", "normal", "depth", "variance", "spp"}
    for name in ["image", "albedo", "normal", "variance"]:
        assert d[name].shape == (32, 32, 3) and d[name].dtype == np.float32, name
    assert d["depth"].shape == (32, 32) and d["spp"].shape == (32, 32)
    assert np.all(d["spp"] == 4)
    assert np.all((d["albedo"] >= 0) & (d["albedo"] <= 1))
    # Normals are means of unit vectors (shorter at edges, 0 where nothing is hit); most of
    # the image is the box.
    lengths = np.linalg.norm(d["normal"], axis=2)
    assert np.all(lengths <= 1.0001) and np.median(lengths) > 0.99
    hit = np.isfinite(d["depth"])
    assert hit.mean() > 0.5 and np.all(d["depth"][hit] > 0)
    assert np.all(lengths[~hit] == 0)
    ours, theirs = tmp_path / "ours.exr", tmp_path / "theirs.exr"
    mcrt.write(ours, d["image"], aovs=d)
    cli("render", CORNELL, "--spp", 4, "--width", 32, "--height", 32, "--seed", 3,
        "--aov", ALL_AOVS, "-o", theirs, "-q")
    assert ours.read_bytes() == theirs.read_bytes()
    # A string list is the same as a list of names.
    again = mcrt.render(CORNELL, spp=4, width=32, height=32, seed=3, aovs="spp")
    assert set(again) == {"image", "spp"} and np.array_equal(again["image"], d["image"])


def test_scene_error_carries_file_line_column(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(CORNELL.read_text().replace("spp = 64", "spp = \"many\"", 1))
    with pytest.raises(mcrt.SceneError) as e:
        mcrt.load(bad)
    msg = str(e.value)
    assert msg == cli_error("render", bad, "-o", tmp_path / "x.png")
    assert msg.startswith(f"{bad}:{e.value.line}:{e.value.column}: ")
    assert e.value.line == 9 and e.value.path == str(bad)
    assert isinstance(e.value, mcrt.Error)
    # render() of a path raises the same.
    with pytest.raises(mcrt.SceneError, match=r":9:\d+: "):
        mcrt.render(bad)


def test_xml_error_and_missing_file(tmp_path):
    scene = tmp_path / "s.xml"
    scene.write_text(LIGHTS_XML.read_text().replace('value="64"', 'value="$nope"', 1))
    with pytest.raises(mcrt.SceneError) as e:
        mcrt.load(scene)
    assert str(e.value) == cli_error("render", scene, "-o", tmp_path / "x.png")
    assert e.value.line is not None and e.value.column is not None
    with pytest.raises(mcrt.SceneError) as e:
        mcrt.load(tmp_path / "missing.toml")
    assert str(e.value) == cli_error("render", tmp_path / "missing.toml", "-o", tmp_path / "x.png")


@pytest.mark.parametrize(
    "kwargs, flags",
    [
        (dict(threads=0), ["--threads", 0]),
        (dict(max_depth=-2), ["--max-depth=-2"]),
        (dict(width=0), ["--width", 0]),
        (dict(camera="nope"), ["--camera", "nope"]),
        (dict(target_noise=-1.0), ["--target-noise=-1"]),
        (dict(photons=10**10), ["--photons", 10**10]),
        (dict(gather_photons=0), ["--gather-photons", 0]),
    ],
)
def test_bad_settings_raise_the_cli_message(tmp_path, kwargs, flags):
    with pytest.raises(mcrt.Error) as e:
        mcrt.render(CORNELL, spp=1, **kwargs)
    assert str(e.value) == cli_error("render", CORNELL, "--spp", 1, "-o", tmp_path / "x.png", *flags)


def test_bad_names_raise_usage_errors():
    for kwargs in [dict(integrator="bogus"), dict(sampler="bogus"), dict(aovs="albedo,bogus"),
                   dict(backend="bogus")]:
        with pytest.raises(mcrt.UsageError):
            mcrt.render(CORNELL, spp=1, width=4, height=4, **kwargs)
    with pytest.raises(mcrt.UsageError):
        mcrt.render(CORNELL, spp=1, width=4, height=4, integrator="sppm", aovs="albedo")


def test_unknown_isa_cap_is_a_usage_error(monkeypatch):
    monkeypatch.setenv("MCRT_MAX_ISA", "sse")
    with pytest.raises(mcrt.UsageError, match="MCRT_MAX_ISA"):
        mcrt.render(CORNELL, spp=1, width=4, height=4)


def test_time_budget_is_checked_as_the_flag():
    for t in [0, -1.0, float("nan"), "0s", "5 parsecs"]:
        with pytest.raises(mcrt.UsageError, match="duration"):
            mcrt.render(CORNELL, width=4, height=4, time=t)
    # A time budget with spp bounds the samples by both.
    d = mcrt.render(CORNELL, width=4, height=4, spp=2, time="1m", aovs="spp")
    assert np.all(d["spp"] == 2)


def test_write_read_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    img = (rng.random((5, 7, 3)) * 4).astype(np.float32)
    mcrt.write(tmp_path / "a.exr", img)
    assert np.array_equal(mcrt.read(tmp_path / "a.exr"), img)
    # float64 input is converted; half floats keep 11 significant bits.
    mcrt.write(tmp_path / "h.exr", img.astype(np.float64), half=True)
    back = mcrt.read(tmp_path / "h.exr")
    assert not np.array_equal(back, img)
    assert np.allclose(back, img, rtol=2**-10, atol=0)
    # PNG: 8-bit sRGB of the clamped values; reading decodes back to linear.
    low = img / 4
    mcrt.write(tmp_path / "a.png", low)
    png = mcrt.read(tmp_path / "a.png")
    assert png.shape == low.shape
    assert np.max(np.abs(png - low)) < 0.005
    # Exposure applies to PNG: +1 stop doubles the (unclamped) values.
    mcrt.write(tmp_path / "b.png", low / 2, exposure=1.0)
    assert np.max(np.abs(mcrt.read(tmp_path / "b.png") - low)) < 0.005


def test_write_errors(tmp_path):
    img = np.zeros((2, 2, 3), np.float32)
    with pytest.raises(mcrt.ImageError, match="unsupported image format"):
        mcrt.write(tmp_path / "a.jpg", img)
    with pytest.raises(mcrt.UsageError, match="shape"):
        mcrt.write(tmp_path / "a.exr", np.zeros((2, 2)))
    with pytest.raises(mcrt.UsageError, match="tone map"):
        mcrt.write(tmp_path / "a.png", img, tonemap="filmic")
    with pytest.raises(mcrt.ImageError):
        mcrt.read(tmp_path / "missing.exr")
    assert not (tmp_path / "a.exr").exists()


def test_compare_equals_cli(tmp_path):
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    mcrt.write(a, mcrt.render(CORNELL, spp=2, width=32, height=32, seed=1))
    mcrt.write(b, mcrt.render(CORNELL, spp=2, width=32, height=32, seed=2))
    m = mcrt.compare(a, b, diff=tmp_path / "ours.png")
    _, out, _ = cli("compare", a, b, "--diff", tmp_path / "theirs.png")
    lines = dict(l.split(None, 1) for l in out.splitlines())
    assert m.rmse == float(lines["RMSE"])
    assert m.rel_mse == float(lines["relMSE"])
    assert m.psnr == float(lines["PSNR"].split()[0])
    assert m.rmse > 0 and abs(m.rmse - m.mse**0.5) < 1e-12
    assert (tmp_path / "ours.png").read_bytes() == (tmp_path / "theirs.png").read_bytes()
    # Arrays work as well as paths; an image against itself has no error.
    same = mcrt.compare(mcrt.read(a), a)
    assert same.rmse == 0 and same.psnr == float("inf")
    with pytest.raises(mcrt.ImageError, match="size|differ|match"):
        mcrt.compare(a, np.zeros((4, 4, 3), np.float32))
    with pytest.raises(mcrt.ImageError) as e:
        mcrt.compare(tmp_path / "ours.png", b)
    assert str(e.value) == cli_error("compare", tmp_path / "ours.png", b)


def test_progress_callback():
    calls = []
    img = mcrt.render(CORNELL, spp=4, width=32, height=32, seed=1,
                      progress=lambda done, total: calls.append((done, total)))
    assert calls, "the callback was never called"
    assert calls[-1] == (32 * 32 * 4, 32 * 32 * 4)
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:]))
    assert img.shape == (32, 32, 3)
    # With a time budget and no spp the total is unknown.
    calls.clear()
    mcrt.render(CORNELL, width=8, height=8, time=0.2, progress=lambda d, t: calls.append(t))
    assert calls and all(t is None for t in calls)


def test_progress_true_renders_with_or_without_tqdm():
    a = mcrt.render(CORNELL, spp=1, width=8, height=8, seed=2, progress=True)
    assert np.array_equal(a, mcrt.render(CORNELL, spp=1, width=8, height=8, seed=2))
    with pytest.raises(mcrt.UsageError, match="progress"):
        mcrt.render(CORNELL, spp=1, width=8, height=8, progress=3)


def test_progress_exception_stops_the_render():
    class Stop(Exception):
        pass

    def cb(done, total):
        raise Stop()

    t = time.monotonic()
    with pytest.raises(Stop):
        mcrt.render(CORNELL, spp=1_000_000, width=64, height=64, progress=cb)
    assert time.monotonic() - t < 20


def test_ctrl_c_interrupts_the_render():
    """SIGINT during a render that would take hours raises KeyboardInterrupt within moments;
    the timer thread that sends it runs because the render released the GIL."""
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    t = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            mcrt.render(CORNELL, spp=1_000_000, width=64, height=64)
    finally:
        timer.cancel()
    assert time.monotonic() - t < 20
    # The module still renders afterwards.
    assert mcrt.render(CORNELL, spp=1, width=8, height=8).shape == (8, 8, 3)


def test_scene_object():
    scene = mcrt.load(CORNELL)
    assert scene.cameras == ["main"]
    assert (scene.width, scene.height, scene.spp) == (256, 256, 64)
    assert scene.path == str(CORNELL)
    assert "mcrt.Scene" in repr(scene)
    # Rendering a Scene twice, and the path, give the same bits.
    a = mcrt.render(scene, spp=1, width=16, height=16, seed=5)
    b = mcrt.render(scene, spp=1, width=16, height=16, seed=5)
    c = mcrt.render(str(CORNELL), spp=1, width=16, height=16, seed=5)
    assert np.array_equal(a, b) and np.array_equal(a, c)
    with pytest.raises(TypeError):
        mcrt.render(42)
