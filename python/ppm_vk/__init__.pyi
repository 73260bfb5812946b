"""Type stubs of ppm_vk (python/ppm_vk/__init__.py has the docstrings)."""

import os
from typing import Any, Callable, Dict, Iterable, List, Literal, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as np

from ._errors import (
    CancelledError as CancelledError,
    CheckpointError as CheckpointError,
    DeviceError as DeviceError,
    Error as Error,
    IoError as IoError,
    LimitError as LimitError,
    MergeError as MergeError,
    SceneError as SceneError,
    SettingsError as SettingsError,
    UnknownSettingError as UnknownSettingError,
)

PathLike = Union[str, os.PathLike[str]]

DEFAULT_PASSES: int

class Image(np.ndarray):
    """A linear RGB image: float32, shape (height, width, 3); Jupyter shows it tone-mapped."""
    def __new__(cls, array: Any) -> Image: ...
    def to_png(self, exposure: float = 0.0) -> bytes: ...
    def save_png(self, path: PathLike, exposure: float = 0.0) -> None: ...
    def _repr_png_(self) -> Optional[bytes]: ...

class PassStats:
    """What one photon pass did and what it cost."""
    index: int
    photons: int
    emitted_total: int
    records: int
    batches: int
    photon_paths_cut: int
    eye_paths_cut: int
    photons_capped: int
    radius_max: float
    cell_size: float
    wall_ms: float
    stage_ms: Dict[str, float]
    def __init__(
        self,
        index: int,
        photons: int,
        emitted_total: int,
        records: int,
        batches: int,
        photon_paths_cut: int,
        eye_paths_cut: int,
        photons_capped: int,
        radius_max: float,
        cell_size: float,
        wall_ms: float,
        stage_ms: Dict[str, float],
    ) -> None: ...

def default_settings() -> Dict[str, Any]:
    """The settings (the engine's field names) and their defaults."""
    ...

def read_exr(path: PathLike) -> Image:
    """Reads an EXR image."""
    ...

class Renderer:
    """A render in progress on one device."""
    progress: Optional[Callable[[PassStats], Any]]
    def __init__(
        self,
        scene: PathLike,
        params: Optional[Mapping[str, Any]] = None,
        *,
        progress: Optional[Callable[[PassStats], Any]] = None,
        resolution: Optional[Tuple[int, int]] = None,
        device: Optional[Union[int, str]] = None,
        validation: bool = False,
        pipeline_cache: Optional[PathLike] = None,
        resume: Optional[PathLike] = None,
        mode: str = ...,
        photons_per_pass: int = ...,
        alpha: float = ...,
        seed: int = ...,
        initial_radius: Optional[float] = ...,
        radius: Optional[float] = ...,
        cone_k: Optional[Union[float, str]] = ...,
        cone: Optional[Union[float, str]] = ...,
        probe: str = ...,
        probe_beta: float = ...,
        beta: float = ...,
        probe_photons: Optional[int] = ...,
        probe_k: float = ...,
        probe_grow: float = ...,
        shrink_z: float = ...,
        caustic_photons: float = ...,
        hit_slots: int = ...,
        rough_splits: int = ...,
        glass_splits: int = ...,
        max_eye_depth: int = ...,
        max_photon_depth: int = ...,
        emission_samples: int = ...,
        pilot_samples: int = ...,
        rough_samples: int = ...,
        direct: str = ...,
        light_samples: int = ...,
        glossy_hits: Optional[Union[float, str]] = ...,
        glossy_light: str = ...,
        specialize: bool = ...,
        max_inline_triangles: int = ...,
        grid_buckets: Optional[int] = ...,
        grid_cell: Optional[float] = ...,
        split_submissions: bool = ...,
        max_tile_bytes: Optional[int] = ...,
    ) -> None: ...
    def pass_(self) -> PassStats: ...
    def render(self, passes: Optional[int] = None, time: Optional[float] = None) -> Image: ...
    def cancel(self) -> None: ...
    def image(self) -> Image: ...
    def save(self, path: PathLike) -> None: ...
    def checkpoint(self, path: PathLike) -> None: ...
    def set_camera(
        self,
        eye: Optional[Sequence[float]] = None,
        look_at: Optional[Sequence[float]] = None,
        up: Optional[Sequence[float]] = None,
        vfov: Optional[float] = None,
    ) -> None: ...
    @property
    def camera(self) -> Dict[str, Any]: ...
    @property
    def passes(self) -> int: ...
    @property
    def settings(self) -> Dict[str, Any]: ...
    @property
    def scene_name(self) -> str: ...
    @property
    def device(self) -> str: ...
    def validation_messages(self) -> List[str]: ...
    def check_validation(self) -> None: ...

def render(
    scene: PathLike,
    time: Optional[float] = None,
    passes: Optional[int] = None,
    params: Optional[Mapping[str, Any]] = None,
    *,
    progress: Optional[Callable[[PassStats], Any]] = None,
    resolution: Optional[Tuple[int, int]] = None,
    device: Optional[Union[int, str]] = None,
    validation: bool = False,
    pipeline_cache: Optional[PathLike] = None,
    **settings: Any,
) -> Image:
    """Renders a scene and returns its image: float32, shape (height, width, 3), linear RGB."""
    ...

METHODS: Tuple[str, str]

class Part:
    """One worker's share of a render; pickles as its file's bytes."""
    @property
    def worker(self) -> int: ...
    @property
    def of(self) -> int: ...
    @property
    def passes(self) -> int: ...
    @property
    def method(self) -> str: ...
    @property
    def scene_name(self) -> str: ...
    @property
    def build(self) -> str: ...
    def to_bytes(self) -> bytes: ...
    def save(self, path: PathLike) -> None: ...

class MergeInfo:
    """What merge combined."""
    scene_name: str
    method: str
    of: int
    workers: List[int]
    missing: List[int]
    passes: int
    photons: int
    def __init__(
        self,
        scene_name: str,
        method: str,
        of: int,
        workers: List[int],
        missing: List[int],
        passes: int,
        photons: int,
    ) -> None: ...

def render_part(
    scene: PathLike,
    worker: int,
    of: int,
    passes: int,
    out: Optional[PathLike] = None,
    method: Literal["probabilistic", "independent"] = "probabilistic",
    params: Optional[Mapping[str, Any]] = None,
    *,
    resolution: Optional[Tuple[int, int]] = None,
    device: Optional[Union[int, str]] = None,
    validation: bool = False,
    pipeline_cache: Optional[PathLike] = None,
    **settings: Any,
) -> Part:
    """Renders worker `worker`'s share of a render split between `of` workers; also writes it to `out`."""
    ...

def load_part(path: PathLike) -> Part:
    """Reads a part file."""
    ...

@overload
def merge(parts: Iterable[Union[Part, PathLike]], *, return_info: Literal[False] = False) -> Image: ...
@overload
def merge(parts: Iterable[Union[Part, PathLike]], *, return_info: Literal[True]) -> Tuple[Image, MergeInfo]: ...
