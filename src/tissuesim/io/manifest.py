"""The output directory of a run: checked before anything is written, and a manifest of what
the run wrote, so the next run into the same directory removes exactly that and nothing else.

``manifest.json`` lists the run's plain files (summary.json, forces.csv, pictures) and its
series (``<name>.pvd`` with its ``<name>_NNNNN.vtu`` frames). A new run into the directory
first replaces summary.json (so no summary ever lists frames that are gone), then removes what
the previous manifest lists, then writes its own. Files the manifest does not list (a user's
notes, another tool's output) are never touched; entries that are not plain names in the
directory (``../x``, ``/etc/x``) are ignored, so a forged manifest cannot reach outside it.
"""

from __future__ import annotations

import json
import os
import re
import secrets
from pathlib import Path

from tissuesim.errors import OutputError
from tissuesim.io.atomic import remove_leftovers, write_json_atomic
from tissuesim.io.series.vtu import remove_series

__all__ = ["prepare_directory", "Manifest", "OUTPUT_FILES", "MANIFEST"]

MANIFEST = "manifest.json"
#: plain files a run may write besides its series
OUTPUT_FILES = ("summary.json", MANIFEST, "forces.csv", "forces.png", "final.png", "run.gif")
OUTPUT_FILES += ("checkpoint.npz", "checkpoint_history.jsonl")  # io/checkpoints/checkpoint.py
_PLAIN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")


def prepare_directory(directory: str | os.PathLike[str]) -> Path:
    """Create ``directory`` if needed and check it can take a run's output; OutputError (with
    the path and what to do) if it is a file, lies under a file, is not writable, or one of
    the names a run writes is taken by a directory."""
    d = Path(directory)
    where = f"output directory {str(d)!r}"
    if d.exists() and not d.is_dir():
        raise OutputError(f"{where} is a file; give a directory (--out) that is not a file")
    for parent in d.parents:
        if parent.exists() and not parent.is_dir():
            raise OutputError(f"{where} lies under {str(parent)!r}, which is a file")
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create {where}: {exc.strerror}; choose another --out") from None
    probe = d / f".tissuesim-write-test-{secrets.token_hex(4)}"
    try:
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise OutputError(
            f"{where} is not writable ({exc.strerror}); fix its permissions or choose another --out"
        ) from None
    for name in OUTPUT_FILES:
        if (d / name).is_dir():
            raise OutputError(
                f"{where}: {name!r} is a directory; a run writes a file of that name: remove or "
                "rename it, or choose another --out"
            )
    return d


class Manifest:
    """What a run wrote into ``directory``; see the module docstring."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory
        self.files: list[str] = []
        self.series: list[str] = []
        self.previous = self._read()

    def _read(self) -> dict[str, list[str]]:
        try:
            data = json.loads((self.directory / MANIFEST).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {"files": [], "series": []}
        if not isinstance(data, dict):
            return {"files": [], "series": []}
        out = {}
        for key in ("files", "series"):
            items = data.get(key, [])
            items = items if isinstance(items, list) else []
            out[key] = [s for s in items if isinstance(s, str) and _PLAIN.fullmatch(s)]
        return out

    def remove_previous(self, keep: tuple[str, ...] = ("summary.json", MANIFEST)) -> list[str]:
        """Delete what the previous run listed (its series index first, then frames, then
        files), except ``keep``, and the temporary files a killed run left (hidden
        ``.NAME.tmp-XXXXXXXX.EXT``: ``io/atomic.py``); returns what was removed."""
        removed = remove_leftovers(self.directory)
        for name in self.previous["series"]:
            remove_series(self.directory, name)
            removed.append(f"{name}.pvd")
        for name in self.previous["files"]:
            if name not in keep and (self.directory / name).is_file():
                (self.directory / name).unlink()
                removed.append(name)
        return removed

    def add(self, *, file: str | None = None, series: str | None = None) -> None:
        """Record a file or series of this run; the manifest is rewritten when it changes."""
        changed = False
        if file is not None and file not in self.files:
            self.files.append(file)
            changed = True
        if series is not None and series not in self.series:
            self.series.append(series)
            changed = True
        if changed:
            self.write()

    def write(self) -> None:
        from tissuesim._version import __version__

        write_json_atomic(
            self.directory / MANIFEST,
            {
                "tissuesim_version": __version__,
                "about": "files and series (<name>.pvd + <name>_NNNNN.vtu) this run wrote; "
                "the next run into this directory removes them",
                "files": [MANIFEST, *[f for f in self.files if f != MANIFEST]],
                "series": self.series,
            },
        )
