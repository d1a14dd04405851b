"""The manifest, the store and the worker's file layout, without a cluster."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from hce_batch.manifest import ManifestError, flag_args, load_manifest
from hce_batch.store import Store
from hce_batch.worker import _lay_out

KEY = "ab" + "0" * 62


def test_flags_repeat_lists_and_drop_false() -> None:
    args = flag_args({"max-level": 1, "multires": ["a*", "b"], "quiet-x": True, "y": False}, "t")
    assert args == ("--max-level", "1", "--multires", "a*", "--multires", "b", "--quiet-x")
    with pytest.raises(ManifestError, match="set by hce-batch"):
        flag_args({"threads": 2}, "t")


def test_a_manifest_expands_globs_against_its_folder(tmp_path: Path) -> None:
    (tmp_path / "in" / "sub").mkdir(parents=True)
    for name in ["a.glb", "b.glb", "sub/c.glb"]:
        (tmp_path / "in" / name).write_bytes(b"x")
    (tmp_path / "m.toml").write_text(
        'store = "s"\n[[bake]]\nfiles = "in/**/*.glb"\noutput = "out/{parent}/{stem}.hce"\n'
        "[bake.params]\nmax-level = 1\n"
    )
    m = load_manifest(tmp_path / "m.toml")
    assert [a.input.name for a in m.assets] == ["a.glb", "b.glb", "c.glb"]
    assert m.assets[2].output == tmp_path / "out/in/sub/c.hce"
    assert m.assets[0].args == ("--max-level", "1")
    assert m.store == str(tmp_path / "s")
    as_json = {"bake": [{"files": ["in/a.glb"], "output": "o/{name}"}]}
    (tmp_path / "m.json").write_text(json.dumps(as_json))
    assert load_manifest(tmp_path / "m.json").assets[0].output == tmp_path / "o/a.glb"


@pytest.mark.parametrize(
    ("entry", "says"),
    [
        ('files = "none/*.glb"\noutput = "{stem}.glb"', "matches no file"),
        ('files = "*.glb"\noutput = "out.glb"', "would both be written"),
        ('files = "*.glb"\noutput = "{stem}.gltf"', "must end in .glb or .hce"),
        ('files = "*.glb"\noutput = "{nope}.glb"', "unknown field"),
    ],
)
def test_a_bad_manifest_says_what_is_wrong(tmp_path: Path, entry: str, says: str) -> None:
    (tmp_path / "a.glb").write_bytes(b"x")
    (tmp_path / "b.glb").write_bytes(b"x")
    (tmp_path / "m.toml").write_text(f"[[bake]]\n{entry}\n")
    with pytest.raises(ManifestError, match=says):
        load_manifest(tmp_path / "m.toml")


def test_the_store_keeps_one_whole_file_per_key(tmp_path: Path) -> None:
    store = Store(str(tmp_path / "store"))
    src = tmp_path / "baked.glb"
    src.write_bytes(b"glTF baked")
    assert not store.exists(KEY, "glb")
    assert store.put(KEY, "glb", src)
    assert store.path(KEY, "glb") == f"{tmp_path}/store/ab/{KEY}.glb"
    assert not store.put(KEY, "glb", src), "a second put of a key stores nothing"
    assert os.listdir(tmp_path / "store" / "ab") == [f"{KEY}.glb"], "no temporary file is left"
    dest = tmp_path / "dest" / "x.glb"
    store.fetch(KEY, "glb", dest)
    assert dest.read_bytes() == b"glTF baked"
    store.fetch(KEY, "glb", dest, link="copy")
    assert dest.read_bytes() == b"glTF baked"
    store.record(KEY, {"worker": "w"})
    assert store.records(KEY) == [{"worker": "w"}]
    with pytest.raises(ValueError, match="not a bake key"):
        store.path("../../etc", "glb")


def test_an_fsspec_store_takes_the_same_calls(tmp_path: Path) -> None:
    store = Store("memory://hce-test-store")
    src = tmp_path / "baked.hce"
    src.write_bytes(b"HCE1")
    assert store.put(KEY, "hce", src)
    assert store.exists(KEY, "hce")
    dest = tmp_path / "d.hce"
    store.fetch(KEY, "hce", dest)
    assert dest.read_bytes() == b"HCE1"
    store.record(KEY, {"n": 1})
    assert store.records(KEY) == [{"n": 1}]


def test_shipped_files_are_laid_out_with_room_for_parent_references(tmp_path: Path) -> None:
    files = (("scene.gltf", b"{}"), ("../textures/t.png", b"png"), ("bin/b.bin", b"bin"))
    scene = _lay_out(files, tmp_path / "asset")
    assert scene.read_bytes() == b"{}"
    assert (scene.parent / "../textures/t.png").resolve().read_bytes() == b"png"
    assert (scene.parent / "bin/b.bin").read_bytes() == b"bin"
    deep = _lay_out((("scene.glb", b""), ("../../x", b"")), tmp_path / "deep")
    assert (deep.parent / "../../x").resolve().is_relative_to(tmp_path / "deep")
    with pytest.raises(ValueError, match="absolute path"):
        _lay_out((("scene.glb", b""), ("/etc/x", b"")), tmp_path / "other")
