"""The batch manifest: which files to bake, with which `hce bake` parameters, to where.

A manifest is a TOML or JSON file; paths in it are relative to its own folder::

    store = "store"                  # optional: the content-addressed store (a folder or URL)

    [[bake]]
    files = ["samples/*.glb"]        # a glob or a list of globs (`**` recurses)
    output = "baked/{stem}.glb"      # per asset: {stem}, {name}, {parent} (relative folder)
    [bake.params]                    # `hce bake` flags without their dashes
    max-level = 1
    multires = ["all"]               # a list repeats the flag; true is a bare flag

Each file an entry's globs match is one asset; a file may be matched by several entries (baked
once per parameter set), but no two assets may share a destination.
"""

from __future__ import annotations

import glob
import json
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

#: Flags the runner sets itself, or that would keep `hce bake` from baking.
RESERVED_FLAGS = frozenset(
    {"output", "o", "report", "print-key", "print-inputs", "quiet", "q", "threads"}
)

#: The output formats a store can hold: one self-contained file each (a `.gltf` names its
#: `.bin` after its own file name, so its bytes would depend on the destination).
OUTPUT_FORMATS = ("glb", "hce")


class ManifestError(ValueError):
    """A manifest that cannot be read or names no valid assets."""


@dataclass(frozen=True)
class Asset:
    """One bake: an input scene, its `hce bake` flags, its destination."""

    input: Path
    output: Path
    args: tuple[str, ...]
    #: The index of the manifest entry that named it.
    entry: int

    @property
    def format(self) -> str:
        return self.output.suffix.lower().lstrip(".")


@dataclass(frozen=True)
class Manifest:
    path: Path
    assets: tuple[Asset, ...]
    #: The store the manifest names, resolved against its folder; `None` when it names none.
    store: str | None


def flag_args(params: dict[str, Any], where: str) -> tuple[str, ...]:
    """`hce bake` flags from a parameter table, in the table's order."""
    args: list[str] = []
    for name, value in params.items():
        if name in RESERVED_FLAGS:
            raise ManifestError(f"{where}: {name!r} is set by hce-batch, not by the manifest")
        flag = f"--{name}"
        values = value if isinstance(value, list) else [value]
        for v in values:
            if v is True:
                args.append(flag)
            elif v is False:
                continue
            elif isinstance(v, (int, float, str)):
                args += [flag, str(v)]
            else:
                raise ManifestError(f"{where}.{name}: {v!r} is not a string, number or boolean")
    return tuple(args)


def _read(path: Path) -> dict[str, Any]:
    try:
        text = path.read_bytes()
    except OSError as e:
        raise ManifestError(f"{path}: cannot read the manifest: {e}") from e
    try:
        if path.suffix.lower() == ".json":
            data = json.loads(text)
        else:
            data = tomllib.loads(text.decode("utf-8"))
    except (ValueError, UnicodeDecodeError) as e:
        raise ManifestError(f"{path}: not a valid manifest: {e}") from e
    if not isinstance(data, dict):
        raise ManifestError(f"{path}: the manifest must be a table (a JSON object)")
    return data


def load_manifest(path: Path) -> Manifest:
    """Reads a manifest and expands its globs into assets, in entry and then file order."""
    data = _read(path)
    base = path.parent
    entries = data.get("bake")
    if not isinstance(entries, list) or not entries:
        raise ManifestError(f"{path}: no [[bake]] entries")
    assets: list[Asset] = []
    destinations: dict[Path, Asset] = {}
    for i, entry in enumerate(entries):
        where = f"{path}: bake[{i}]"
        if not isinstance(entry, dict):
            raise ManifestError(f"{where} is not a table")
        patterns = entry.get("files")
        if isinstance(patterns, str):
            patterns = [patterns]
        if not isinstance(patterns, list) or not all(isinstance(p, str) for p in patterns):
            raise ManifestError(f"{where}.files: a glob or a list of globs")
        template = entry.get("output")
        if not isinstance(template, str):
            raise ManifestError(f"{where}.output: a destination such as 'baked/{{stem}}.glb'")
        params = entry.get("params", {})
        if not isinstance(params, dict):
            raise ManifestError(f"{where}.params: a table of `hce bake` flags")
        args = flag_args(params, f"{where}.params")
        for pattern in patterns:
            matches = sorted(glob.glob(str(base / pattern), recursive=True))
            files = [Path(m) for m in matches if Path(m).is_file()]
            if not files:
                raise ManifestError(f"{where}.files: {pattern!r} matches no file")
            for f in files:
                try:
                    parent = f.parent.relative_to(base).as_posix()
                except ValueError:
                    parent = f.parent.as_posix()
                try:
                    dest = base / template.format(stem=f.stem, name=f.name, parent=parent)
                except (KeyError, IndexError, ValueError) as e:
                    raise ManifestError(
                        f"{where}.output: {template!r} uses an unknown field ({e}); use "
                        "{stem}, {name} or {parent}"
                    ) from e
                asset = Asset(input=f, output=dest, args=args, entry=i)
                if asset.format not in OUTPUT_FORMATS:
                    raise ManifestError(
                        f"{where}.output: {dest} must end in .glb or .hce (one file per asset)"
                    )
                if dest in destinations:
                    other = destinations[dest]
                    raise ManifestError(
                        f"{where}: {f} and {other.input} (bake[{other.entry}]) would both be "
                        f"written to {dest}"
                    )
                destinations[dest] = asset
                assets.append(asset)
    store = data.get("store")
    if store is not None and not isinstance(store, str):
        raise ManifestError(f"{path}: store: a folder or an fsspec URL")
    if store is not None and "://" not in store:
        store = str(base / store)
    return Manifest(path=path, assets=tuple(assets), store=store)
