"""The Python package against the `ppm-vk` binary and the engine's error cases, on the default device
(lavapipe in CI) with the Vulkan validation layer on, as the Rust tests run (tests/common/mod.rs): every
render here passes validation=True and fails on any message. Small images and few passes: lavapipe is slow."""

import ast
import dataclasses
import pathlib
import struct
import threading
import time

import numpy as np
import pytest

import ppm_vk
from conftest import CORNELL, REPO

# A small render that still has every stage: 48 x 40 pixels, 20000 photons a pass.
SMALL = dict(resolution=(48, 40), photons_per_pass=20_000, validation=True)


def small(cache_dir, **extra):
    return dict(SMALL, pipeline_cache=cache_dir, **extra)


def cli_flags(seed, passes):
    w, h = SMALL["resolution"]
    return ["--resolution", f"{w}x{h}", "--photons-per-pass", SMALL["photons_per_pass"], "--seed", seed,
            "--passes", passes, "--validate", "--force"]


def test_render_is_the_cli_image_bit_for_bit(tmp_path, cache_dir, cli):
    exr, png = tmp_path / "cli.exr", tmp_path / "cli.png"
    cli("render", CORNELL, *cli_flags(7, 3), "--out", exr)
    cli("render", CORNELL, *cli_flags(7, 3), "--out", png)
    image = ppm_vk.render(CORNELL, passes=3, seed=7, **small(cache_dir))
    expected = ppm_vk.read_exr(exr)
    assert image.shape == expected.shape == (40, 48, 3)
    assert image.tobytes() == expected.tobytes(), "the Python render differs from the CLI's"
    # The inline image is the PNG `render --out x.png` writes, byte for byte.
    assert image._repr_png_() == png.read_bytes()
    # The comparison can fail: another seed gives another image.
    other = ppm_vk.render(CORNELL, passes=3, seed=8, **small(cache_dir))
    assert other.tobytes() != image.tobytes()


def test_mitsuba_params_are_the_cli_defines(tmp_path, cache_dir, cli):
    scene = REPO / "scenes" / "point-box.xml"
    exr = tmp_path / "cli.exr"
    cli("render", scene, "-D", "res=24", "--photons-per-pass", 20_000, "--passes", 2, "--validate", "--out", exr)
    image = ppm_vk.render(scene, passes=2, params={"res": 24}, photons_per_pass=20_000, validation=True,
                          pipeline_cache=cache_dir)
    assert image.shape == (24, 24, 3)
    assert image.tobytes() == ppm_vk.read_exr(exr).tobytes()


def test_flag_names_and_off_are_the_cli_settings(tmp_path, cache_dir, cli):
    exr = tmp_path / "cli.exr"
    cli("render", CORNELL, *cli_flags(3, 2), "--radius", 0.05, "--cone", 1.5, "--glossy-hits", "off", "--mode",
        "ppm", "--out", exr)
    # numpy scalars are their values.
    renderer = ppm_vk.Renderer(CORNELL, radius=0.05, cone=1.5, glossy_hits="off", mode="ppm", seed=np.uint32(3),
                               **small(cache_dir))
    settings = renderer.settings
    assert (settings["initial_radius"], settings["cone_k"], settings["glossy_hits"], settings["mode"]) == (
        pytest.approx(0.05), 1.5, None, "ppm")
    assert renderer.render(passes=2).tobytes() == ppm_vk.read_exr(exr).tobytes()


def test_image_is_float32_height_width_3(cache_dir):
    renderer = ppm_vk.Renderer(CORNELL, **small(cache_dir))
    stats = renderer.pass_()
    image = renderer.image()
    assert isinstance(image, np.ndarray) and isinstance(image, ppm_vk.Image)
    assert image.shape == (40, 48, 3) and image.dtype == np.float32 and image.flags.c_contiguous
    assert np.isfinite(image).all() and image.mean() > 0
    # The PNG is the image's size: its IHDR holds width and height.
    png = image._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and struct.unpack(">II", png[16:24]) == (48, 40)
    assert isinstance(stats, ppm_vk.PassStats) and stats.index == 1 and stats.photons == 20_000
    assert stats.wall_ms > 0 and stats.stage_ms["gather"] > 0
    renderer.check_validation()


def test_progress_sees_every_pass_and_save_writes_the_image(tmp_path, cache_dir):
    seen = []
    renderer = ppm_vk.Renderer(CORNELL, progress=seen.append, **small(cache_dir))
    image = renderer.render(passes=2)
    assert [s.index for s in seen] == [1, 2] and renderer.passes == 2
    renderer.save(tmp_path / "out.exr")
    assert ppm_vk.read_exr(tmp_path / "out.exr").tobytes() == image.tobytes()


def test_set_camera_restarts_the_render(cache_dir):
    renderer = ppm_vk.Renderer(CORNELL, **small(cache_dir))
    first = renderer.render(passes=2)
    camera = renderer.camera
    renderer.set_camera(eye=[camera["eye"][0] + 0.5, *camera["eye"][1:]])
    assert renderer.passes == 0
    moved = renderer.render(passes=2)
    assert moved.tobytes() != first.tobytes()
    # Back where it was: the same image as before the move, bit for bit.
    renderer.set_camera(eye=camera["eye"])
    assert renderer.render(passes=2).tobytes() == first.tobytes()
    with pytest.raises(ppm_vk.SceneError) as bad:
        renderer.set_camera(vfov=200.0)
    assert "vfov" in bad.value.field


def test_a_checkpoint_resumes_bit_for_bit_and_refuses_another_render(tmp_path, cache_dir):
    ckpt = tmp_path / "render.ckpt"
    renderer = ppm_vk.Renderer(CORNELL, **small(cache_dir))
    renderer.render(passes=1)
    renderer.checkpoint(ckpt)
    whole = renderer.render(passes=3)
    resumed = ppm_vk.Renderer(CORNELL, resume=ckpt, **small(cache_dir))
    assert resumed.passes == 1
    assert resumed.render(passes=3).tobytes() == whole.tobytes()
    # Another seed, a damaged file, no file: refused before the device opens.
    with pytest.raises(ppm_vk.CheckpointError) as e:
        ppm_vk.Renderer(CORNELL, resume=ckpt, **small(cache_dir, seed=5))
    assert "seed" in str(e.value)
    damaged = tmp_path / "damaged.ckpt"
    damaged.write_bytes(ckpt.read_bytes()[:-100])
    with pytest.raises(ppm_vk.CheckpointError):
        ppm_vk.Renderer(CORNELL, resume=damaged, **small(cache_dir))
    with pytest.raises(ppm_vk.IoError) as e:
        ppm_vk.Renderer(CORNELL, resume=tmp_path / "none.ckpt", **small(cache_dir))
    assert e.value.filename == str(tmp_path / "none.ckpt")
    with pytest.raises(ppm_vk.IoError):
        renderer.checkpoint(tmp_path / "no-such-dir" / "r.ckpt")


def test_a_bad_scene_is_a_scene_error_with_file_line_column_field(tmp_path, cache_dir):
    lines = CORNELL.read_text().splitlines()
    n = next(i for i, l in enumerate(lines) if l.lstrip().startswith("radius"))
    lines[n] = "radius = -1.0"
    bad = tmp_path / "bad.toml"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(ppm_vk.SceneError) as e:
        ppm_vk.Renderer(bad, pipeline_cache=cache_dir)
    err = e.value
    assert (err.file, err.line, err.column, err.field) == (str(bad), n + 1, len("radius = ") + 1, "sphere[0].radius")
    assert isinstance(err, ppm_vk.Error) and "positive" in str(err)


def test_an_unknown_define_is_a_scene_error(cache_dir):
    with pytest.raises(ppm_vk.SceneError):
        ppm_vk.Renderer(REPO / "scenes" / "point-box.xml", params={"no_such_param": 1}, pipeline_cache=cache_dir)


def test_a_missing_file_is_an_io_error(tmp_path, cache_dir):
    missing = tmp_path / "no-such-scene.toml"
    with pytest.raises(ppm_vk.IoError) as e:
        ppm_vk.Renderer(missing, pipeline_cache=cache_dir)
    assert isinstance(e.value, OSError) and e.value.filename == str(missing)
    renderer = ppm_vk.Renderer(CORNELL, **small(cache_dir))
    with pytest.raises(ppm_vk.IoError):
        renderer.save(tmp_path / "no-such-dir" / "out.exr")
    with pytest.raises(ppm_vk.IoError):
        renderer.save(tmp_path / "out.bmp")


def test_bad_settings_name_their_field(cache_dir):
    with pytest.raises(TypeError) as e:
        ppm_vk.Renderer(CORNELL, photons=10, pipeline_cache=cache_dir)
    assert isinstance(e.value, ppm_vk.UnknownSettingError) and e.value.field == "photons" and "photons" in str(e.value)
    with pytest.raises(ppm_vk.SettingsError) as e:
        ppm_vk.Renderer(CORNELL, alpha=1.5, pipeline_cache=cache_dir)
    assert e.value.field == "alpha" and isinstance(e.value, ValueError)
    with pytest.raises(ppm_vk.SettingsError) as e:
        ppm_vk.Renderer(CORNELL, mode="bidirectional", pipeline_cache=cache_dir)
    assert e.value.field == "mode"
    with pytest.raises(ppm_vk.SettingsError) as e:
        ppm_vk.Renderer(CORNELL, photons_per_pass=(1 << 24) + 1, pipeline_cache=cache_dir)
    assert e.value.field == "photons_per_pass"
    with pytest.raises(ppm_vk.SettingsError) as e:
        ppm_vk.Renderer(CORNELL, resolution=(0, 8), pipeline_cache=cache_dir)
    assert e.value.field == "resolution"
    with pytest.raises(ppm_vk.SettingsError) as e:
        ppm_vk.Renderer(CORNELL, alpha=float("nan"), pipeline_cache=cache_dir)
    assert e.value.field == "alpha"
    with pytest.raises(ppm_vk.SettingsError) as e:
        ppm_vk.Renderer(CORNELL, seed=object(), pipeline_cache=cache_dir)
    assert e.value.field == "seed"
    with pytest.raises(ppm_vk.SettingsError):
        ppm_vk.render(CORNELL, passes=1, time=1.0, pipeline_cache=cache_dir)


def test_a_device_limit_is_a_limit_error(cache_dir):
    # 4096 x 4096 pixels with 8 hit points each: far past any device's largest storage buffer (as
    # tests/errors.rs).
    with pytest.raises(ppm_vk.LimitError) as e:
        ppm_vk.Renderer(CORNELL, resolution=(4096, 4096), hit_slots=8, validation=True, pipeline_cache=cache_dir)
    err = e.value
    assert err.value is not None and err.value > err.limit > 0 and "resolution" in err.lower


def test_an_unknown_device_is_a_device_error(cache_dir):
    with pytest.raises(ppm_vk.DeviceError):
        ppm_vk.Renderer(CORNELL, device="no-such-device-anywhere", pipeline_cache=cache_dir)


def test_cancel_ends_a_pass_and_the_render_goes_on(cache_dir):
    renderer = ppm_vk.Renderer(CORNELL, **small(cache_dir))
    renderer.pass_()
    before = renderer.image()
    renderer.cancel()
    with pytest.raises(ppm_vk.CancelledError):
        renderer.pass_()
    assert renderer.passes == 1 and renderer.image().tobytes() == before.tobytes()
    # From another thread, while a long pass runs (16 batches of 2^20 photons; the pass checks between them):
    # on lavapipe it takes tens of seconds, so the cancel lands in it.
    big = ppm_vk.Renderer(CORNELL, **small(cache_dir, photons_per_pass=1 << 24))
    timer = threading.Timer(0.5, big.cancel)
    timer.start()
    try:
        big.pass_()
        finished = True
    except ppm_vk.CancelledError:
        finished = False
    timer.join()
    if finished:
        # A device that finished 2^24 photons within 0.5 s: the cancel ends the next pass instead.
        with pytest.raises(ppm_vk.CancelledError):
            big.pass_()
    assert big.passes == (1 if finished else 0)
    # The next pass goes on.
    assert renderer.pass_().index == 2
    renderer.check_validation()
    big.check_validation()


def test_the_gil_is_released_while_a_pass_runs(cache_dir):
    # A pass long enough to tell (0.2 s): 400k photons on lavapipe, more on a faster device.
    for photons in (400_000, 1 << 24):
        renderer = ppm_vk.Renderer(CORNELL, **small(cache_dir, photons_per_pass=photons))
        stamps, stop = [], threading.Event()

        def tick():
            while not stop.is_set():
                stamps.append(time.monotonic())
                time.sleep(0.001)

        thread = threading.Thread(target=tick)
        thread.start()
        try:
            start = time.monotonic()
            renderer.pass_()
            end = time.monotonic()
        finally:
            stop.set()
            thread.join()
        if end - start > 0.2:
            break
    assert end - start > 0.2, "the pass was too short to tell"
    # Holding the GIL, the pass would have kept the thread from running at all between its start and end.
    inside = [t for t in stamps if start + 0.05 < t < end - 0.05]
    assert len(inside) >= 10, f"{len(inside)} ticks of another Python thread during a {end - start:.2f} s pass"
    renderer.check_validation()


def test_time_renders_at_least_one_pass(cache_dir):
    renderer = ppm_vk.Renderer(CORNELL, **small(cache_dir))
    image = renderer.render(time=0.001)
    # The pass started in time finishes, as `render --time`.
    assert renderer.passes >= 1 and image.mean() > 0


def test_images_in_and_out(tmp_path):
    with pytest.raises(ppm_vk.IoError) as e:
        ppm_vk.read_exr(tmp_path / "none.exr")
    assert e.value.filename == str(tmp_path / "none.exr")
    # The tone mapping: 0 and 1 are the ends of sRGB, 2**-exposure scales.
    image = ppm_vk.Image(np.array([[[0.0, 1.0, 0.5]]], dtype=np.float32))
    assert ppm_vk.Image(image * 2).to_png(-1.0) == image.to_png()
    with pytest.raises(ppm_vk.SettingsError) as e:
        image.to_png(float("nan"))
    assert e.value.field == "exposure"
    assert ppm_vk.Image(np.zeros((4, 4), dtype=np.float32))._repr_png_() is None


def test_the_stubs_match_the_package():
    """__init__.pyi names what the package has, and its Renderer keywords are the engine's settings (and
    the flag names), so editors complete what runs."""
    stub = ast.parse((pathlib.Path(ppm_vk.__file__).parent / "__init__.pyi").read_text())
    top = {n.name: n for n in stub.body if isinstance(n, (ast.ClassDef, ast.FunctionDef))}
    assert set(top) >= {"render", "Renderer", "Image", "PassStats", "read_exr", "default_settings"}
    for name in top:
        assert hasattr(ppm_vk, name), name
    stub_methods = {n.name for n in top["Renderer"].body if isinstance(n, ast.FunctionDef)}
    public = {m for m in dir(ppm_vk.Renderer) if not m.startswith("_")}
    assert public == stub_methods - {"__init__"}
    init = next(n for n in top["Renderer"].body if isinstance(n, ast.FunctionDef) and n.name == "__init__")
    keywords = {a.arg for a in init.args.kwonlyargs} - {"progress", "resolution", "device", "validation",
                                                       "pipeline_cache", "resume"}
    assert keywords == set(ppm_vk.default_settings()) | {"radius", "beta", "cone"}
    assert {f.name for f in dataclasses.fields(ppm_vk.PassStats)} == {
        n.target.id for n in top["PassStats"].body if isinstance(n, ast.AnnAssign)}
