"""Ensembles on a Dask cluster: the bodies split into chunks, each chunk integrated by
``liemid.ensemble`` on a worker, the results gathered in order. Per-body results do not
depend on the chunking or the worker, so the bits equal those of a local run."""

from __future__ import annotations

from typing import Any, Dict, Optional

import numpy as np
from numpy.typing import ArrayLike

from ._core import EnsembleState, RigidBody, _ensemble_states, ensemble as _local

__all__ = ["ensemble"]


def _chunk(body: RigidBody, att_name: str, att: Any, mom_name: str, mom: Any, kwargs: Dict[str, Any]) -> EnsembleState:
    return _local(body, **{att_name: att, mom_name: mom}, **kwargs)


def ensemble(
    client: Any,
    body: RigidBody,
    rotations: Optional[ArrayLike] = None,
    angular_velocities: Optional[ArrayLike] = None,
    *,
    rotation_vectors: Optional[ArrayLike] = None,
    quaternions: Optional[ArrayLike] = None,
    angular_momenta: Optional[ArrayLike] = None,
    t_end: float,
    step: float,
    method: str = "liemid-ea",
    t0: float = 0.0,
    chunk_size: int = 10_000,
    threads_per_task: int = 1,
    max_steps: Optional[int] = None,
) -> EnsembleState:
    """``liemid.ensemble`` on the workers of a ``dask.distributed.Client``: the same
    arguments, plus ``chunk_size`` bodies per task and ``threads_per_task``."""
    att_name, att, mom_name, mom = _ensemble_states(rotations, rotation_vectors, quaternions, angular_velocities, angular_momenta)
    n = att.shape[0]
    if chunk_size < 1:
        raise ValueError(f"chunk_size: must be at least 1, found {chunk_size}")
    kwargs: Dict[str, Any] = dict(t_end=t_end, step=step, method=method, t0=t0, threads=threads_per_task, max_steps=max_steps)
    starts = range(0, n, chunk_size)
    futures = [
        client.submit(_chunk, body, att_name, att[s : s + chunk_size], mom_name, mom[s : s + chunk_size], kwargs, pure=False)
        for s in starts
    ]
    parts = client.gather(futures)
    return EnsembleState(
        t=float(t_end),
        pi=np.concatenate([p.pi for p in parts]),
        rotation=np.concatenate([p.rotation for p in parts]),
    )
