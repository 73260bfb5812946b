"""Shared fixtures: the repository, the `ppm-vk` binary the CLI comparisons run, and one pipeline cache
for the session (as tests/common/mod.rs gives its binaries one), so neither the tests nor the user's
cache see each other's kernels."""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
CORNELL = REPO / "scenes" / "cornell-spheres.toml"


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("pipeline-cache")


@pytest.fixture(scope="session")
def cli(cache_dir):
    """Runs the `ppm-vk` binary ($PPM_VK_BIN, else the release build of this checkout)."""
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    binary = pathlib.Path(os.environ.get("PPM_VK_BIN", target / "release" / "ppm-vk"))
    if not binary.is_file():
        pytest.fail(f"{binary} is missing: build it with `cargo build --release` (or set PPM_VK_BIN)")

    def run(*args):
        env = dict(os.environ, PPM_VK_CACHE_DIR=str(cache_dir))
        env.setdefault("XDG_RUNTIME_DIR", "/tmp")
        done = subprocess.run([str(binary), *map(str, args)], env=env, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, f"ppm-vk {' '.join(map(str, args))} failed:\n{done.stderr}"
        return done

    return run
