"""One image from many machines on a Ray cluster (docs/distributed.md).

:func:`render` runs the workers of a render as Ray tasks, each rendering its part
(:func:`ppm_vk.render_part`) on the device of the node Ray placed it on, and merges the parts on the
driver. Ray schedules, retries and moves the parts; this module only says what each task renders::

    import ppm_vk.distributed
    image = ppm_vk.distributed.render("scenes/cornell-spheres.toml", workers=8, passes=50)

Ray is an optional dependency (``pip install 'ppm-vk[ray]'``, or ``pip install ray``), imported when a
render starts.
"""

from __future__ import annotations

import os
from typing import Any, Mapping, Optional

from . import Part, PathLike, SettingsError, load_part, merge, render_part

__all__ = ["render"]


def _ray() -> Any:
    """The ``ray`` module, or an ImportError that says how to install it."""
    try:
        import ray
    except ImportError as e:
        raise ImportError(
            "ppm_vk.distributed needs Ray: pip install 'ppm-vk[ray]' (or pip install ray) "
            f"into this environment and the cluster's ({e})"
        ) from e
    return ray


def _task(scene: str, worker: int, of: int, passes: int, parts_dir: Optional[str], kwargs: dict) -> Any:
    """One Ray task: worker ``worker``'s part, returned (pickled as its file's bytes), or written to
    ``parts_dir`` and its path returned."""
    out = None
    if parts_dir is not None:
        out = os.path.join(parts_dir, f"{os.path.basename(scene)}.worker-{worker}-of-{of}.part")
    part = render_part(scene, worker, of, passes, out=out, **kwargs)
    return part if out is None else out


def render(
    scene: PathLike,
    workers: int,
    passes: int,
    address: Optional[str] = None,
    *,
    parts_dir: Optional[PathLike] = None,
    task_options: Optional[Mapping[str, Any]] = None,
    return_info: bool = False,
    **settings: Any,
) -> Any:
    """Renders ``scene`` as ``workers`` Ray tasks of ``passes`` photon passes each and returns the merged
    :class:`ppm_vk.Image` (with ``return_info=True``, the pair (image, :class:`ppm_vk.MergeInfo`)). With
    the probabilistic method (the default) the image is one machine's render of ``workers * passes``
    passes bit for bit, wherever the tasks ran (every node running the same build of ppm_vk).

    ``address``: the cluster to join, ``ray.init(address=address)``, when Ray is not yet initialised in
    this process (``None`` starts a local cluster on this machine, or joins the one ``RAY_ADDRESS`` names).
    ``scene`` (and the files it names) must be readable at the same path on every node.
    ``parts_dir``: a directory shared by the nodes; each task then writes its part there
    (``<scene>.worker-K-of-N.part``, files ``ppm-vk merge`` reads) instead of returning it through Ray's
    object store. ``task_options``: Ray's options for each task (``{"num_gpus": 1}`` on a GPU cluster, so
    that Ray places one task per device; the default is one CPU a task). The other keywords are
    :func:`ppm_vk.render_part`'s: ``method``, ``params``, ``resolution``, ``device``, ``pipeline_cache``,
    and the settings.
    """
    for name, value in (("workers", workers), ("passes", passes)):
        # Refused here rather than in every task (the engine checks the rest of the share).
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise SettingsError(f"settings: {name}: expected a whole number >= 1, got {value!r}", field=name)
    ray = _ray()
    if not ray.is_initialized():
        ray.init(address=address)
    scene = os.fspath(scene)
    shared = None if parts_dir is None else os.fspath(parts_dir)
    task = ray.remote(_task)
    if task_options:
        task = task.options(**task_options)
    futures = [task.remote(scene, k, workers, passes, shared, settings) for k in range(workers)]
    parts = ray.get(futures)
    loaded = [p if isinstance(p, Part) else load_part(p) for p in parts]
    return merge(loaded, return_info=return_info)
