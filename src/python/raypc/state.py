"""The render state (docs/state.md) as Python reads, edits and writes it. The compiled module's
one state schema checks it, so that a bad state gets the command line's message."""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Iterable, Optional, Union

from . import _raypc
from ._raypc import Error, NotFoundError

STATE_VERSION: int = _raypc.state_version()  # of the state document this package writes


class State:
    """A render state (docs/state.md): the view, colours, brushes, step … as the browser UI saves
    it. Made from a dict (without "version": this version's), a JSON text, a JSON file (path) or
    another State, and checked by the one state schema, with its messages (:class:`raypc.Error`). Top-level fields read and write as
    attributes (``state.step = 3``, ``state.brushes.append({"name": "depth", "min": 560, "max":
    760})``); a change is checked again when the state is used or by :meth:`validate`."""

    def __init__(self, source: Union[None, dict, str, os.PathLike, "State"] = None):
        if source is None:
            document: Any = {}
        elif isinstance(source, State):
            document = source.to_dict()
        elif isinstance(source, dict):
            document = source
        elif isinstance(source, os.PathLike) or (isinstance(source, str) and not source.lstrip().startswith("{")):
            path = Path(source)
            try:
                text = path.read_text()
            except OSError as e:
                shown = str(path) if len(str(path)) <= 120 else f"{str(path)[:80]}… ({len(str(path))} characters)"
                kind = NotFoundError if isinstance(e, FileNotFoundError) else Error
                raise kind(f"{shown}: cannot read the state ({e.strerror})") from None
            object.__setattr__(self, "_doc", json.loads(_raypc.check_state(text)))
            return
        elif isinstance(source, str):
            object.__setattr__(self, "_doc", json.loads(_raypc.check_state(source)))
            return
        else:
            raise TypeError(f"State: expected a dict, JSON text, path or State, not {type(source).__name__}")
        if isinstance(document, dict) and "version" not in document:
            document = dict(document, version=STATE_VERSION)  # written here, for this version
        object.__setattr__(self, "_doc", json.loads(_raypc.check_state(json.dumps(document))))

    def validate(self) -> "State":
        """Checks the state again (after edits) and normalises it; returns self."""
        object.__setattr__(self, "_doc", json.loads(_raypc.check_state(json.dumps(self._doc))))
        return self

    def to_dict(self) -> dict:
        """A deep copy of the document."""
        return json.loads(json.dumps(self._doc))

    def to_json(self, indent: Optional[int] = 2) -> str:
        return json.dumps(self.validate()._doc, indent=indent)

    def save(self, path: Union[str, os.PathLike]) -> None:
        """Writes the state as the UI's Save state does (``raypc render --state`` reads it)."""
        Path(path).write_text(self.to_json() + "\n")

    def __getattr__(self, name: str) -> Any:
        doc = object.__getattribute__(self, "_doc")
        if name in doc:
            return doc[name]
        raise AttributeError(f"State has no field '{name}' (fields: {', '.join(doc)})")

    def __setattr__(self, name: str, value: Any) -> None:
        previous = self._doc.get(name, None)
        had = name in self._doc
        self._doc[name] = value
        try:
            self.validate()
        except Error:
            if had:
                self._doc[name] = previous
            else:
                del self._doc[name]
            raise

    def __dir__(self) -> Iterable[str]:
        return list(super().__dir__()) + list(self._doc)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, State) and self.to_dict() == other.to_dict()

    def __repr__(self) -> str:
        doc = self._doc
        color = doc.get("color", {}).get("variable") or "(first variable)"
        brushes = ", ".join(f"{b['name']} {b['min']:g}..{b['max']:g}" for b in doc.get("brushes", []))
        return f"raypc.State(step={doc.get('step')}, color={color!r}, brushes=[{brushes}])"
