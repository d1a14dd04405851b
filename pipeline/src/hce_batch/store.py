"""The content-addressed store: one file per bake key, `ab/abcdef....glb` under its root.

A file appears under its key whole or not at all: it is written to a temporary name in the same
folder and renamed, so a worker killed mid-write leaves at most a stray temporary file, never a
half file under a key. The root is a local folder or, for workers on other machines, any fsspec
URL (`s3://bucket/hce`, `memory://...`); there the rename is the file system's `mv`, atomic
where the file system's rename is. Every bake that stored an output also leaves a record,
`log/<key>/<id>.json` (its hce report, the worker and the time), so a store says how often each
key was baked.
"""

from __future__ import annotations

import json
import os
import shutil
import uuid
from pathlib import Path
from typing import Any

import fsspec


def _is_url(root: str) -> bool:
    return "://" in root and not root.startswith("file://")


class Store:
    def __init__(self, root: str) -> None:
        self.root = root.removeprefix("file://") if not _is_url(root) else root
        self.local = not _is_url(root)
        self._fs: Any = None if self.local else fsspec.core.url_to_fs(self.root)[0]

    def __repr__(self) -> str:
        return f"Store({self.root!r})"

    def relative(self, key: str, fmt: str) -> str:
        """The path of a key's file within the store."""
        if len(key) != 64 or any(c not in "0123456789abcdef" for c in key):
            raise ValueError(f"{key!r} is not a bake key (64 lower-case hex digits)")
        return f"{key[:2]}/{key}.{fmt}"

    def _join(self, rel: str) -> str:
        return f"{self.root.rstrip('/')}/{rel}"

    def path(self, key: str, fmt: str) -> str:
        return self._join(self.relative(key, fmt))

    def exists(self, key: str, fmt: str) -> bool:
        target = self.path(key, fmt)
        if self.local:
            return os.path.isfile(target)
        return bool(self._fs.exists(target))

    def put(self, key: str, fmt: str, source: Path) -> bool:
        """Stores `source` under `key`; `False` when the key already held a file (its bytes are
        the same: equal keys, equal bakes)."""
        target = self.path(key, fmt)
        if self.exists(key, fmt):
            return False
        tmp = f"{os.path.dirname(target)}/.{key}.{uuid.uuid4().hex}.tmp"
        if self.local:
            os.makedirs(os.path.dirname(target), exist_ok=True)
            try:
                with open(source, "rb") as src, open(tmp, "wb") as dst:
                    shutil.copyfileobj(src, dst)
                    dst.flush()
                    os.fsync(dst.fileno())
                os.replace(tmp, target)
            finally:
                if os.path.exists(tmp):
                    os.unlink(tmp)
        else:
            self._fs.makedirs(os.path.dirname(target), exist_ok=True)
            self._fs.put_file(str(source), tmp)
            self._fs.mv(tmp, target)
        return True

    def fetch(self, key: str, fmt: str, dest: Path, link: str = "auto") -> None:
        """Puts the key's file at `dest`, replacing what was there atomically: a hard link into
        a local store (`link="hard"`, or `"auto"` where the file systems allow it), a symbolic
        link (`"symlink"`), or a copy (`"copy"`, and `"auto"` otherwise)."""
        source = self.path(key, fmt)
        dest.parent.mkdir(parents=True, exist_ok=True)
        tmp = dest.parent / f".{dest.name}.{uuid.uuid4().hex}.tmp"
        try:
            if self.local and link in ("auto", "hard"):
                try:
                    os.link(source, tmp)
                except OSError:
                    if link == "hard":
                        raise
                    shutil.copyfile(source, tmp)
            elif self.local and link == "symlink":
                os.symlink(os.path.abspath(source), tmp)
            elif self.local:
                shutil.copyfile(source, tmp)
            else:
                self._fs.get_file(source, str(tmp))
            os.replace(tmp, dest)
        finally:
            if os.path.lexists(tmp):
                os.unlink(tmp)

    def record(self, key: str, entry: dict[str, Any]) -> None:
        """Leaves the record of one bake of `key` (see the module documentation)."""
        rel = f"log/{key}/{uuid.uuid4().hex}.json"
        text = json.dumps(entry, indent=1, sort_keys=True)
        target = self._join(rel)
        if self.local:
            os.makedirs(os.path.dirname(target), exist_ok=True)
            tmp = f"{target}.tmp"
            with open(tmp, "w", encoding="utf-8") as f:
                f.write(text)
            os.replace(tmp, target)
        else:
            self._fs.makedirs(os.path.dirname(target), exist_ok=True)
            self._fs.pipe_file(target, text.encode("utf-8"))

    def records(self, key: str) -> list[dict[str, Any]]:
        """Every bake record of `key`."""
        folder = self._join(f"log/{key}")
        out: list[dict[str, Any]] = []
        if self.local:
            if not os.path.isdir(folder):
                return out
            for name in sorted(os.listdir(folder)):
                if name.endswith(".json"):
                    with open(os.path.join(folder, name), encoding="utf-8") as f:
                        out.append(json.load(f))
        elif self._fs.exists(folder):
            for name in sorted(self._fs.ls(folder, detail=False)):
                if str(name).endswith(".json"):
                    out.append(json.loads(self._fs.cat_file(name)))
        return out
