"""One image from many machines from Python (docs/distributed.md): parts rendered by `render_part` merge into
one machine's render bit for bit, in any order, through objects, files, bytes or pickles; mismatched parts
are a MergeError; and a local Ray cluster of two workers renders and merges the same image end to end."""

import pickle
import sys

import numpy as np
import pytest

import ppm_vk
import ppm_vk.distributed
from conftest import CORNELL

# Tiny renders (lavapipe is slow, and each part opens its own device): 32 x 32 pixels, 4000 photons a pass.
TINY = dict(resolution=(32, 32), photons_per_pass=4000, seed=3)
WORKERS, PASSES = 2, 2


def tiny(cache_dir, **extra):
    return dict(TINY, pipeline_cache=cache_dir, **extra)


@pytest.fixture(scope="module")
def parts(cache_dir):
    """Worker 0 and 1 of 2, two passes each."""
    return [ppm_vk.render_part(CORNELL, k, WORKERS, PASSES, **tiny(cache_dir)) for k in range(WORKERS)]


@pytest.fixture(scope="module")
def single(cache_dir):
    """One machine's render of all the passes: the one worker of one."""
    return ppm_vk.render_part(CORNELL, 0, 1, WORKERS * PASSES, **tiny(cache_dir))


def test_parts_merge_into_one_machines_render_bit_for_bit(parts, single):
    image, info = ppm_vk.merge(parts, return_info=True)
    expected = ppm_vk.merge([single])
    assert isinstance(image, ppm_vk.Image) and image.shape == (32, 32, 3) and image.dtype == np.float32
    assert image.mean() > 0, "the merged image is black"
    assert image.tobytes() == expected.tobytes(), "two workers' parts differ from one machine's render"
    assert info == ppm_vk.MergeInfo(scene_name="cornell-spheres", method="probabilistic", of=2, workers=[0, 1],
                                    missing=[], passes=4, photons=4 * TINY["photons_per_pass"])
    assert [(p.worker, p.of, p.passes, p.method) for p in parts] == [(0, 2, 2, "probabilistic"),
                                                                      (1, 2, 2, "probabilistic")]


def test_merge_is_order_independent_through_files_bytes_and_pickles(tmp_path, parts):
    a, b = parts
    image = ppm_vk.merge([a, b])
    assert ppm_vk.merge([b, a]).tobytes() == image.tobytes()
    a.save(tmp_path / "a.part")
    assert ppm_vk.load_part(tmp_path / "a.part").to_bytes() == a.to_bytes() == (tmp_path / "a.part").read_bytes()
    copy = pickle.loads(pickle.dumps(b))
    assert isinstance(copy, ppm_vk.Part) and copy.to_bytes() == b.to_bytes()
    assert ppm_vk.merge([copy, tmp_path / "a.part"]).tobytes() == image.tobytes()
    # Some of the workers: an image of fewer passes, the others listed as missing.
    half, info = ppm_vk.merge([b], return_info=True)
    assert (info.workers, info.missing, info.passes) == ([1], [0], 2)
    assert half.tobytes() != image.tobytes()


def test_mismatched_parts_are_a_merge_error_saying_which(tmp_path, cache_dir, parts, single):
    a, b = parts
    reseeded = ppm_vk.render_part(CORNELL, 1, WORKERS, PASSES, **tiny(cache_dir, seed=4))
    with pytest.raises(ppm_vk.MergeError, match=r"worker 1 of 2's part was rendered with other settings \(seed: 4"):
        ppm_vk.merge([a, reseeded])
    with pytest.raises(ppm_vk.MergeError, match="worker 0 of 2 is given twice"):
        ppm_vk.merge([a, a])
    with pytest.raises(ppm_vk.MergeError, match="split between 2 workers, worker 0 of 1's between 1"):
        ppm_vk.merge([single, a])
    with pytest.raises(ppm_vk.MergeError, match="no parts to merge"):
        ppm_vk.merge([])
    damaged = bytearray(a.to_bytes())
    damaged[-40] ^= 1
    (tmp_path / "damaged.part").write_bytes(bytes(damaged))
    with pytest.raises(ppm_vk.MergeError, match="does not match its checksum"):
        ppm_vk.merge([tmp_path / "damaged.part", b])
    (tmp_path / "no.part").write_bytes(b"not a part at all")
    with pytest.raises(ppm_vk.MergeError, match="not a ppm-vk part"):
        ppm_vk.load_part(tmp_path / "no.part")
    with pytest.raises(ppm_vk.IoError) as e:
        ppm_vk.merge([tmp_path / "missing.part"])
    assert e.value.filename == str(tmp_path / "missing.part")


def test_bad_shares_are_settings_errors_before_any_device_opens(cache_dir):
    with pytest.raises(ppm_vk.SettingsError, match="worker 2 of 2: workers count from 0 to 1") as e:
        ppm_vk.render_part(CORNELL, 2, 2, 1, **tiny(cache_dir))
    assert e.value.field == "worker"
    with pytest.raises(ppm_vk.SettingsError) as e:
        ppm_vk.render_part(CORNELL, 0, 2, 1, method="sppm", **tiny(cache_dir))
    assert e.value.field == "method"
    with pytest.raises(ppm_vk.SettingsError) as e:
        ppm_vk.render_part(CORNELL, -1, 2, 1, **tiny(cache_dir))
    assert e.value.field == "worker"
    with pytest.raises(ppm_vk.SettingsError) as e:
        ppm_vk.distributed.render(CORNELL, workers=0, passes=1)
    assert e.value.field == "workers"


def test_without_ray_distributed_render_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # as if Ray were not installed
    with pytest.raises(ImportError, match=r"needs Ray: pip install 'ppm-vk\[ray\]'"):
        ppm_vk.distributed.render(CORNELL, workers=1, passes=1)


def test_a_local_ray_cluster_of_two_workers_renders_one_machines_image(tmp_path, cache_dir, single):
    # Imported here so that a missing Ray fails this test (scripts/python-install installs it), never skips.
    import ray

    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        image, info = ppm_vk.distributed.render(CORNELL, workers=WORKERS, passes=PASSES, return_info=True,
                                                **tiny(cache_dir))
        # The tasks write their parts to a shared directory instead of returning them.
        shared = ppm_vk.distributed.render(CORNELL, workers=WORKERS, passes=PASSES, parts_dir=tmp_path,
                                           **tiny(cache_dir))
    finally:
        ray.shutdown()
    expected = ppm_vk.merge([single])
    assert image.tobytes() == expected.tobytes(), "the Ray render differs from one machine's"
    assert shared.tobytes() == expected.tobytes()
    assert (info.workers, info.missing, info.passes) == ([0, 1], [], 4)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "cornell-spheres.toml.worker-0-of-2.part", "cornell-spheres.toml.worker-1-of-2.part"]
