"""ppm_vk: progressive photon mapping (photon probing, cone filter) on Vulkan compute, from Python.

Render a scene into a numpy array (float32, shape (height, width, 3), linear RGB)::

    import ppm_vk
    image = ppm_vk.render("scenes/cornell-spheres.toml", passes=20, photons_per_pass=200_000)
    image              # in Jupyter, shows itself (tone-mapped sRGB)

or drive the passes yourself with :class:`Renderer`. Settings are keywords named as the engine's
``Settings`` fields (``photons_per_pass``, ``alpha``, ``seed``, ``initial_radius``, ``cone_k``, ``probe``,
...; ``ppm_vk.default_settings()`` lists them) or as the ``render`` command's flags where those differ
(``radius``, ``beta``, ``cone``), plus ``resolution=(width, height)``; the defaults are ``render``'s. The
device: ``device`` (index or name substring), ``validation`` (the Vulkan validation layer, as the tests run
it), ``pipeline_cache`` (a directory; the ``render`` command's by default).

Errors are :class:`Error` subclasses, one per case of the engine's error: :class:`SceneError` (with
``file``, ``line``, ``column``, ``field``), :class:`SettingsError`, :class:`LimitError`,
:class:`DeviceError`, :class:`IoError` (an ``OSError``), :class:`CheckpointError`,
:class:`CancelledError`, :class:`MergeError`.

One image from many machines: :func:`render_part` renders one worker's share of a render, :func:`merge`
combines the parts (those of the probabilistic method into one machine's image bit for bit), and
:func:`ppm_vk.distributed.render` runs the workers as Ray tasks (docs/distributed.md).
"""

from __future__ import annotations

import dataclasses
import json
import os
import time as _time
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._errors import (
    CancelledError,
    CheckpointError,
    DeviceError,
    Error,
    IoError,
    LimitError,
    MergeError,
    SceneError,
    SettingsError,
    UnknownSettingError,
)

__all__ = [
    "render",
    "Renderer",
    "Image",
    "PassStats",
    "read_exr",
    "default_settings",
    "render_part",
    "load_part",
    "merge",
    "Part",
    "MergeInfo",
    "Error",
    "SceneError",
    "SettingsError",
    "UnknownSettingError",
    "LimitError",
    "DeviceError",
    "IoError",
    "CheckpointError",
    "CancelledError",
    "MergeError",
]

PathLike = Union[str, "os.PathLike[str]"]

#: Passes a render has when neither ``passes`` nor ``time`` is given (as the ``render`` command).
DEFAULT_PASSES = 100


class Image(np.ndarray):
    """A linear RGB image: a float32 numpy array of shape (height, width, 3) that Jupyter shows as the
    tone-mapped PNG the ``render`` command writes (:meth:`to_png`)."""

    def __new__(cls, array: Any) -> "Image":
        return np.asarray(array, dtype=np.float32).view(cls)

    def to_png(self, exposure: float = 0.0) -> bytes:
        """The image as an 8-bit sRGB PNG: scaled by 2**exposure, clamped to [0, 1], sRGB-encoded (the
        engine's own tone mapping, as ``render --out x.png``)."""
        return _native.encode_png(np.ascontiguousarray(self.view(np.ndarray), dtype=np.float32), float(exposure))

    def save_png(self, path: PathLike, exposure: float = 0.0) -> None:
        """Writes :meth:`to_png` to ``path``."""
        with open(path, "wb") as f:
            f.write(self.to_png(exposure))

    def _repr_png_(self) -> Optional[bytes]:
        # A slice that is no longer an RGB image shows as an array.
        if self.ndim != 3 or self.shape[2] != 3 or self.size == 0:
            return None
        return self.to_png()


@dataclasses.dataclass(frozen=True)
class PassStats:
    """What one photon pass did and what it cost (the engine's ``PassStats``)."""

    #: 1 for the first photon pass.
    index: int
    #: Photons this pass emitted.
    photons: int
    #: Photons all passes so far emitted.
    emitted_total: int
    #: Photon records this pass left on diffuse surfaces.
    records: int
    #: Batches the pass was split into.
    batches: int
    #: Photon paths of the render so far ended at the depth backstop.
    photon_paths_cut: int
    #: Eye paths of the render so far ended at the depth backstop.
    eye_paths_cut: int
    #: Times a photon's flux was held at the shading-normal correction's cap, over the render so far.
    photons_capped: int
    #: The largest search radius after this pass.
    radius_max: float
    #: The photon grid's cell size for the next pass.
    cell_size: float
    #: Host wall time of the pass in the engine, submission to completion (ms).
    wall_ms: float
    #: GPU milliseconds per stage ("ray", "photon", "lookup/count", ..., "update").
    stage_ms: Dict[str, float]


def default_settings() -> Dict[str, Any]:
    """The settings (the engine's field names) and their defaults, as ``render`` has them."""
    return json.loads(_native.default_settings_json())


def read_exr(path: PathLike) -> Image:
    """Reads an EXR image (a render, a reference) as an :class:`Image`."""
    return Image(_native.read_exr(os.fspath(path)))


def _defines(params: Optional[Mapping[str, Any]]) -> list:
    """``params`` as the ``render`` command's ``-D name=value`` pairs (booleans as Mitsuba writes them)."""
    out = []
    for name, value in (params or {}).items():
        if isinstance(value, bool):
            value = "true" if value else "false"
        out.append((str(name), str(value)))
    return out


class Renderer:
    """A render in progress on one device: the scene loaded, the kernels compiled, the first eye pass
    (and the probe pass) done. Each :meth:`pass_` adds a photon pass; :meth:`image` is the estimate so far.

    ``scene`` is a TOML or Mitsuba XML file; ``params`` sets a Mitsuba scene's ``$name`` defaults
    (``{"res": 256}``, as ``render -D res=256``). ``progress``, if given, is called with each pass's
    :class:`PassStats`. ``resume`` continues a :meth:`checkpoint` (or ``render --checkpoint``) of the same
    scene, settings and build, bit for bit; one that does not fit is a :class:`CheckpointError`. The device
    works with the GIL released, and :meth:`cancel` may be called from another thread while a pass runs.
    """

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
        **settings: Any,
    ) -> None:
        if resolution is not None:
            resolution = _resolution(resolution)
        self._native = _native.Renderer(
            os.fspath(scene),
            _defines(params),
            _settings_json(settings),
            resolution,
            _device(device, validation, pipeline_cache),
            None if resume is None else os.fspath(resume),
        )
        self.progress = progress

    def pass_(self) -> PassStats:
        """One photon pass (with its eye pass in SPPM); returns its statistics. Raises
        :class:`CancelledError` if :meth:`cancel` ended it: the render is then as the passes before it
        left it, and the next call goes on."""
        stats = PassStats(**self._native.pass_())
        if self.progress is not None:
            self.progress(stats)
        return stats

    def render(self, passes: Optional[int] = None, time: Optional[float] = None) -> "Image":
        """Passes until the render has ``passes`` of them (:data:`DEFAULT_PASSES` when neither is given),
        or for ``time`` seconds of passes (the last pass started in time finishes), as the ``render``
        command; returns the image. With ``validation=True``, any validation message is a
        :class:`DeviceError`."""
        _check_length(passes, time)
        target = passes if passes is not None else (None if time is not None else DEFAULT_PASSES)
        start = _time.monotonic()
        while target is None or self.passes < target:
            if time is not None and _time.monotonic() - start >= time:
                break
            self.pass_()
        image = self.image()
        self.check_validation()
        return image

    def cancel(self) -> None:
        """Ends the pass in flight (or the next one) with :class:`CancelledError`; safe from any thread."""
        self._native.cancel()

    def image(self) -> Image:
        """The current estimate: float32, shape (height, width, 3), linear RGB."""
        return Image(self._native.image())

    def save(self, path: PathLike) -> None:
        """Writes the current image: ``.exr`` (linear float) or ``.png`` (tone-mapped sRGB), as ``render``."""
        self._native.save(os.fspath(path))

    def checkpoint(self, path: PathLike) -> None:
        """Saves the whole state of the render to ``path``, for ``Renderer(..., resume=path)`` or ``ppm-vk
        render --resume`` of the same build (written atomically)."""
        self._native.checkpoint(os.fspath(path))

    def set_camera(
        self,
        eye: Optional[Sequence[float]] = None,
        look_at: Optional[Sequence[float]] = None,
        up: Optional[Sequence[float]] = None,
        vfov: Optional[float] = None,
    ) -> None:
        """Moves the camera (the parts given; ``vfov`` in degrees) and starts the render again from its
        first pass: the same image after the same passes as a new renderer of the moved camera, without
        compiling or uploading again. A bad camera is a :class:`SceneError` naming its field."""
        vec = lambda v: None if v is None else [float(x) for x in v]  # noqa: E731
        self._native.set_camera(vec(eye), vec(look_at), vec(up), None if vfov is None else float(vfov))

    @property
    def camera(self) -> Dict[str, Any]:
        """The camera: eye, look_at, up, vfov (degrees), width, height."""
        return self._native.camera()

    @property
    def passes(self) -> int:
        """Photon passes done."""
        return self._native.passes

    @property
    def settings(self) -> Dict[str, Any]:
        """The settings in force (the engine's field names)."""
        return json.loads(self._native.settings_json())

    @property
    def scene_name(self) -> str:
        """The scene's name."""
        return self._native.scene_name

    @property
    def device(self) -> str:
        """The device: name, kind, driver."""
        return self._native.device

    def validation_messages(self) -> list:
        """What the validation layer reported so far (empty unless ``validation=True``)."""
        return self._native.validation_messages()

    def check_validation(self) -> None:
        """Raises :class:`DeviceError` listing the validation layer's messages, if any (as ``render
        --validate`` fails)."""
        msgs = self.validation_messages()
        if msgs:
            raise DeviceError(
                f"the validation layer reported {len(msgs)} message(s):\n" + "\n".join(msgs),
                context="validation",
            )


def _settings_json(settings: Mapping[str, Any]) -> str:
    """The keyword settings as the JSON object the extension reads (numpy scalars as their Python values)."""
    plain = {}
    for name, value in settings.items():
        if isinstance(value, np.generic):
            value = value.item()
        try:
            json.dumps(value, allow_nan=False)
        except (TypeError, ValueError):
            raise SettingsError(f"settings: {name}: cannot use {value!r}", field=name) from None
        plain[name] = value
    return json.dumps(plain)


def _check_length(passes: Optional[int], time: Optional[float]) -> None:
    """How long a render is: passes or seconds, as ``render --passes`` or ``--time``."""
    if passes is not None and time is not None:
        raise SettingsError("settings: give passes or time, not both", field="time")
    if time is not None and not (time > 0 and np.isfinite(time)):
        raise SettingsError(f"settings: time: must be a positive number of seconds, got {time}", field="time")
    if passes is not None and passes < 1:
        raise SettingsError(f"settings: passes: must be at least 1, got {passes}", field="passes")


def _resolution(resolution: Any) -> Tuple[int, int]:
    try:
        w, h = resolution
        if int(w) != w or int(h) != h:
            raise ValueError
        return int(w), int(h)
    except (TypeError, ValueError):
        raise SettingsError(
            f"settings: resolution: expected (width, height), got {resolution!r}", field="resolution"
        ) from None


def render(
    scene: PathLike,
    time: Optional[float] = None,
    passes: Optional[int] = None,
    params: Optional[Mapping[str, Any]] = None,
    *,
    progress: Optional[Callable[[PassStats], Any]] = None,
    **settings: Any,
) -> Image:
    """Renders ``scene`` (TOML or Mitsuba XML; ``params`` for its ``$name`` defaults) for ``passes`` photon
    passes (default 100) or ``time`` seconds, with ``settings`` as keywords (see the module's help and
    :func:`default_settings`), and returns the image: float32, shape (height, width, 3), linear RGB.
    The same scene, seed and settings give the same image bit for bit as the ``render`` command."""
    _check_length(passes, time)  # before the device opens
    renderer = Renderer(scene, params, progress=progress, **settings)
    return renderer.render(passes=passes, time=time)


#: One worker's share of a render (:func:`render_part`, :func:`load_part`): ``worker``, ``of``, ``passes``,
#: ``method``, ``scene_name``, ``build``; :meth:`Part.save` writes its file, :meth:`Part.to_bytes` gives the
#: file's bytes. It pickles as those bytes, so it can be returned from another process (a Ray task).
Part = _native.Part

#: The ways a render is split between workers (docs/distributed.md).
METHODS = ("probabilistic", "independent")


@dataclasses.dataclass(frozen=True)
class MergeInfo:
    """What :func:`merge` combined."""

    scene_name: str
    #: "probabilistic" or "independent".
    method: str
    #: Workers the render was split between.
    of: int
    #: The workers merged, in order, and those not given (a merge of some of them is an image of fewer
    #: passes).
    workers: List[int]
    missing: List[int]
    #: Photon passes in the merged image, and the photons they emitted.
    passes: int
    photons: int


def render_part(
    scene: PathLike,
    worker: int,
    of: int,
    passes: int,
    out: Optional[PathLike] = None,
    method: str = "probabilistic",
    params: Optional[Mapping[str, Any]] = None,
    *,
    resolution: Optional[Tuple[int, int]] = None,
    device: Optional[Union[int, str]] = None,
    validation: bool = False,
    pipeline_cache: Optional[PathLike] = None,
    **settings: Any,
) -> "Part":
    """Renders worker ``worker``'s share (from 0) of a render of ``scene`` split between ``of`` workers,
    ``passes`` photon passes of its own, as ``ppm-vk render --worker K --of N`` does, and returns it as a
    :class:`Part` (also written to ``out`` when given: a file ``ppm-vk merge`` reads). ``method``:
    ``"probabilistic"`` renders passes K, K+N, ... of probabilistic PPM, which merge into one machine's
    image of N x passes bit for bit; ``"independent"`` renders the mode's progressive render with the
    worker's own seed, and the merge averages the images. The other arguments are :func:`render`'s
    (every worker of a render must be given the same). The device works with the GIL released."""
    if method not in METHODS:
        raise SettingsError(f"settings: method: {method!r}: expected one of {METHODS}", field="method")
    part = _native.render_part(
        os.fspath(scene),
        _defines(params),
        _settings_json(settings),
        None if resolution is None else _resolution(resolution),
        _device(device, validation, pipeline_cache),
        (method, _count("worker", worker), _count("of", of), _count("passes", passes)),
    )
    if out is not None:
        part.save(os.fspath(out))
    return part


def load_part(path: PathLike) -> "Part":
    """Reads a part file (``render --worker``'s, :meth:`Part.save`'s): an :class:`IoError` if it cannot be
    read, a :class:`MergeError` if it is damaged or no part."""
    return _native.load_part(os.fspath(path))


def merge(parts: Iterable[Union["Part", PathLike]], *, return_info: bool = False) -> Any:
    """Merges parts of one render (:class:`Part` objects or part files, in any order: the image is the same
    bit for bit) into its image, as ``ppm-vk merge`` does. Parts of other scenes, settings, builds,
    methods or shares, and a worker given twice, are refused with a :class:`MergeError` saying which;
    missing workers are allowed (the image then has fewer passes). Returns the :class:`Image`, or with
    ``return_info=True`` the pair (image, :class:`MergeInfo`)."""
    loaded = [p if isinstance(p, Part) else load_part(p) for p in parts]
    image, info = _native.merge(loaded)
    image = Image(image)
    return (image, MergeInfo(**info)) if return_info else image


def _count(name: str, value: Any) -> int:
    """A whole number >= 0 for the native call (its range is the engine's to check, naming the field)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise SettingsError(f"settings: {name}: expected a whole number >= 0, got {value!r}", field=name)
    return int(value)


def _device(device: Optional[Union[int, str]], validation: bool, pipeline_cache: Optional[PathLike]) -> tuple:
    """The device arguments the extension takes: name or index, validation, pipeline cache directory."""
    return (
        None if device is None else str(device),
        bool(validation),
        None if pipeline_cache is None else os.fspath(pipeline_cache),
    )
