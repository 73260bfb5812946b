"""The exceptions of ppm_vk: one per case of the engine's error (crates/scene/src/error.rs), each a
``ppm_vk.Error`` and, where Python has one, the builtin a program would catch (``OSError``,
``ValueError``, ``TypeError``). The extension raises them with the case's fields as attributes."""

from __future__ import annotations

from typing import Optional


class Error(Exception):
    """Every error ppm_vk raises; ``str(e)`` is the engine's one-line message."""


class SceneError(Error, ValueError):
    """A scene that cannot be rendered. ``file``, ``line`` and ``column`` (1-based; 0 for a scene refused as
    a whole) say where, ``field`` is the path of the field (``sphere[1].radius``; empty for the scene)."""

    def __init__(self, message: str, *, file: str = "", line: int = 0, column: int = 0, field: str = "") -> None:
        super().__init__(message)
        self.file = file
        self.line = line
        self.column = column
        self.field = field


class SettingsError(Error, ValueError):
    """A render setting out of its range or of the wrong type; ``field`` names it."""

    def __init__(self, message: str, *, field: str = "") -> None:
        super().__init__(message)
        self.field = field


class UnknownSettingError(SettingsError, TypeError):
    """A keyword that is no setting (``field``), a ``TypeError`` as for any unexpected keyword."""


class LimitError(Error):
    """Something this device cannot hold or run: ``what`` needs ``value`` (None when the device only said a
    limit was reached) where the device allows ``limit``; ``lower`` says what to lower."""

    def __init__(
        self, message: str, *, what: str = "", value: Optional[int] = None, limit: int = 0, lower: str = ""
    ) -> None:
        super().__init__(message)
        self.what = what
        self.value = value
        self.limit = limit
        self.lower = lower


class DeviceError(Error):
    """A Vulkan or driver failure; ``context`` says during what."""

    def __init__(self, message: str, *, context: str = "") -> None:
        super().__init__(message)
        self.context = context


class IoError(Error, OSError):
    """A file that could not be read or written, or whose content could not be decoded; ``filename`` is
    its path, ``errno`` the system's error number where there is one."""

    def __init__(self, message: str, *, filename: str = "", errno: Optional[int] = None) -> None:
        OSError.__init__(self, message)
        self.filename = filename
        self.errno = errno
        self.strerror = message
        self._message = message

    def __str__(self) -> str:
        # OSError's own would write "[Errno n] strerror: filename"; the engine's message says it all.
        return self._message


class CheckpointError(Error):
    """A checkpoint that cannot be resumed: damaged, or of another scene, setting or build."""


class MergeError(Error):
    """Parts that cannot be merged: of other scenes, settings, builds, methods or shares of the render, a
    worker given twice, or a part file that is damaged or no part; ``str(e)`` is the engine's message,
    naming which."""


class CancelledError(Error):
    """``Renderer.cancel()`` ended the pass in flight; the render keeps the passes before it."""


# Shown (in tracebacks, reprs) as the package's, where they are meant to be caught.
for _cls in (Error, SceneError, SettingsError, UnknownSettingError, LimitError, DeviceError, IoError,
             CheckpointError, MergeError, CancelledError):
    _cls.__module__ = "ppm_vk"
del _cls
