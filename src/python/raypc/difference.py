"""Differences of runs and of steps (``raypc diff``, docs/compare.md "Differences"): a difference
dataset written by the same code as the command line, returned as the lazy xarray Dataset of its
directory (CF names and coordinates, as ``xr.open_dataset(out, engine="raypc")``)."""
from __future__ import annotations

import os
from typing import Iterable, Optional, Union

from . import _raypc
from ._progress import _Progress

PathLike = Union[str, os.PathLike]


def diff(a: PathLike, b: Optional[PathLike], out: PathLike, variables: Optional[Iterable[str]] = None,
         steps: Optional[int] = None, match: str = "index", progress: bool = True):
    """Writes the difference dataset ``a − b`` into ``out`` (as ``raypc diff A B -o OUT``) and returns
    it as an xarray Dataset.

    ``b`` on another grid is read at ``a``'s grid points through the sampler's rule (missing where ``b``
    has no data); ``b=None`` with ``steps=k`` gives the step differences ``a(t) − a(t−k)`` for t ≥ k.
    ``variables``: the display names to difference (default: the stored variables both have; derived
    ones are derived again). ``match``: pair the steps by ``"index"`` or by ``"time"``. A refusal (grids
    that do not overlap, no variable in common, other steps or times, ``out`` holding another dataset)
    raises :class:`raypc.Error` with the command line's message. The variables keep their names and
    units (so that brushes and presets apply); each one's ``comment`` says what it is the difference of
    ("temperature of a.ds − b.ds"), and the Dataset's ``raypc_difference`` attribute what the manifest
    records (A, B, the variables, the step pairs)."""
    import json

    import xarray as xr

    bar = _Progress("diff", progress)
    try:
        _raypc.diff(os.fspath(a), "" if b is None else os.fspath(b), os.fspath(out),
                    list(variables or []), int(steps or 0), match, bar)
    finally:
        bar.close()
    x = xr.open_dataset(os.fspath(out), engine="raypc")
    with open(os.path.join(os.fspath(out), "dataset.json"), encoding="utf-8") as f:
        manifest = json.load(f)
    described = {v["name"]: v.get("long_name", "") for v in manifest["variables"]}
    for name in x.data_vars:
        comment = described.get(x[name].attrs.get("long_name"), "")
        if comment:
            x[name].attrs["comment"] = comment
    x.attrs["raypc_difference"] = json.dumps(manifest["difference"], ensure_ascii=False)
    return x
