"""Opening what ``raypc serve`` opens: a dataset directory as it is, netCDF files or ASPECT's output
preprocessed into one first, with ``raypc preprocess``'s options given as keywords."""
from __future__ import annotations

import os
from typing import Any, Optional, Union

from . import _raypc
from ._progress import _Progress
from ._raypc import Error
from .dataset import Dataset


def _options_to_args(options: dict) -> list:
    """Keyword options as the command line's: time_units="seconds" -> --time-units seconds."""
    args = []
    for key, value in options.items():
        flag = "--" + key.replace("_", "-")
        if value is True:
            args.append(flag)
        elif value is False or value is None:
            continue
        elif isinstance(value, (list, tuple)):
            for item in value:
                args += [flag, str(item)]
        else:
            args += [flag, str(value)]
    return args


def open(*paths: Union[str, os.PathLike], dataset: Optional[Union[str, os.PathLike]] = None,
         progress: bool = True, **options: Any) -> "Dataset":
    """Opens a dataset directory (``raypc preprocess``), or netCDF files / directories of ``*.nc``,
    or ASPECT's output (``solution.pvd`` or its directory), which are preprocessed first as
    ``raypc serve`` does (into ``dataset``, default beside the first file; a complete earlier
    result is reused). ``options`` are ``raypc preprocess``'s, named with underscores, e.g.
    ``raypc.open("output/solution.pvd", time_units="seconds", grid="90x101x180")``.
    Ctrl-C (KeyboardInterrupt) stops preprocessing between steps; a later call resumes."""
    if not paths:
        raise Error("open: give a dataset directory, netCDF files or an ASPECT .pvd")
    args = [os.fspath(p) for p in paths]
    if dataset is not None:
        args += ["--dataset", os.fspath(dataset)]
    args += _options_to_args(options)
    bar = _Progress("preprocessing", progress)
    try:
        directory = _raypc.prepare(args, bar)
    finally:
        bar.close()
    return Dataset(directory)
