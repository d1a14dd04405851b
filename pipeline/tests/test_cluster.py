"""The batch on a real Dask cluster: a scheduler and two worker processes on 127.0.0.1.

One batch of 23 small assets (the samples and generated rooms) and a damaged one is baked while
a worker is killed in the middle of a bake; then the checks: every output byte-identical to a
local `hce bake`, nothing lost and nothing baked twice into the store, the damaged asset failed
alone with hce's status and message, a rerun bakes nothing, and inputs shipped to the workers
bake as they do in place. Every wait is bounded, so a hung cluster fails the test instead of
hanging it.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import subprocess
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import distributed
import psutil
import pytest

from conftest import REPO
from hce_batch.cli import main as cli_main
from hce_batch.manifest import Manifest, load_manifest
from hce_batch.runner import BatchResult, run_batch
from hce_batch.store import Store

#: Low-cost bake flags: the tests are about the batch, not the lighting.
CHEAP: dict[str, Any] = {
    "max-level": 1,
    "bf-epsilon": 0.05,
    "visibility-rays": 1,
    "detail-level": 4,
}
#: Small closed meshes of the repository's own, each in a room at several turns.
MESHES = ["tetrahedron", "octahedron", "icosahedron", "cube_creased", "bipyramid9"]
TURNS = [0, 30, 60, 90]
#: Bounds on the waits: one bake, the whole batch, finding a bake to kill.
BAKE_TIMEOUT = 300.0
BATCH_TIMEOUT = 900.0
KILL_WAIT = 120.0


def _toml_params() -> str:
    return "\n".join(f"{k} = {json.dumps(v)}" for k, v in CHEAP.items())


def _flags() -> list[str]:
    return [x for k, v in CHEAP.items() for x in (f"--{k}", str(v))]


@dataclass
class Batch:
    root: Path
    manifest: Manifest
    store: Store
    damaged: Path


@pytest.fixture(scope="module")
def batch(tmp_path_factory: pytest.TempPathFactory, gen_samples: str) -> Batch:
    root = tmp_path_factory.mktemp("batch")
    (root / "in" / "samples").mkdir(parents=True)
    for glb in sorted((REPO / "samples").glob("*.glb")):
        shutil.copy(glb, root / "in" / "samples" / glb.name)
    (root / "in" / "rooms").mkdir()
    jobs = [
        [
            gen_samples,
            "room",
            "--mesh",
            str(REPO / "geometry" / "tests" / "data" / f"{mesh}.obj"),
            "-o",
            str(root / "in" / "rooms" / f"{mesh}-{turn}.glb"),
            "--turn",
            str(turn),
        ]
        for mesh in MESHES
        for turn in TURNS
    ]
    with ThreadPoolExecutor(max_workers=2) as pool:
        for proc in pool.map(lambda c: subprocess.run(c, capture_output=True, timeout=120), jobs):
            assert proc.returncode == 0, proc.stderr
    (root / "in" / "damaged").mkdir()
    cornell = (REPO / "samples" / "cornell-box.glb").read_bytes()
    damaged = root / "in" / "damaged" / "broken.glb"
    damaged.write_bytes(cornell[: len(cornell) // 3])
    (root / "batch.toml").write_text(
        'store = "store"\n\n'
        f'[[bake]]\nfiles = ["in/samples/*.glb", "in/rooms/*.glb"]\noutput = "out/{{stem}}.glb"\n'
        f"[bake.params]\n{_toml_params()}\n\n"
        f'[[bake]]\nfiles = "in/damaged/*.glb"\noutput = "out/damaged/{{stem}}.glb"\n'
        f"[bake.params]\n{_toml_params()}\n"
    )
    manifest = load_manifest(root / "batch.toml")
    assert manifest.store is not None
    return Batch(root=root, manifest=manifest, store=Store(manifest.store), damaged=damaged)


@pytest.fixture(scope="module")
def cluster() -> Iterator[distributed.LocalCluster]:
    c = distributed.LocalCluster(  # type: ignore[no-untyped-call]
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    )
    try:
        yield c
    finally:
        c.close(timeout=60)


@pytest.fixture(scope="module")
def client(cluster: distributed.LocalCluster) -> Iterator[distributed.Client]:
    c = distributed.Client(cluster, timeout=60)  # type: ignore[no-untyped-call]
    try:
        yield c
    finally:
        c.close()  # type: ignore[no-untyped-call]


@dataclass
class FirstRun:
    result: BatchResult
    #: The bake whose worker was killed: its input, hce's pid, the worker's pid.
    killed: dict[str, Any] | None


def _kill_a_worker_mid_bake(hce: str, stop: threading.Event) -> dict[str, Any] | None:
    """Waits for a bake (an `hce bake ... --report` under a worker process) that has run a
    moment, and kills its worker process with SIGKILL."""
    me = psutil.Process()
    deadline = time.monotonic() + KILL_WAIT
    while time.monotonic() < deadline and not stop.is_set():
        for p in me.children(recursive=True):
            try:
                cmd = p.cmdline()
                age = time.time() - p.create_time()
                parent = p.parent()
            except psutil.Error:
                continue
            if cmd[:2] != [hce, "bake"] or "--report" not in cmd or parent is None:
                continue
            if age < 0.3:
                continue
            info = {"input": cmd[2], "hce_pid": p.pid, "worker_pid": parent.pid}
            parent.kill()
            return info
        time.sleep(0.05)
    return None


@pytest.fixture(scope="module")
def first_run(batch: Batch, client: distributed.Client, hce_bin: str) -> FirstRun:
    stop = threading.Event()
    killed: list[dict[str, Any] | None] = []
    killer = threading.Thread(
        target=lambda: killed.append(_kill_a_worker_mid_bake(hce_bin, stop)), daemon=True
    )
    killer.start()
    try:
        result = run_batch(
            batch.manifest,
            client,
            hce=hce_bin,
            store=batch.store,
            bake_threads=1,
            retries=2,
            timeout=BAKE_TIMEOUT,
            batch_timeout=BATCH_TIMEOUT,
            stream=io.StringIO(),
        )
    finally:
        stop.set()
        killer.join(timeout=10)
    return FirstRun(result=result, killed=killed[0] if killed else None)


def _local_bake(hce: str, src: Path, out: Path) -> bytes:
    proc = subprocess.run(
        [hce, "bake", str(src), "-o", str(out), "-q", *_flags()],
        capture_output=True,
        text=True,
        timeout=BAKE_TIMEOUT,
    )
    assert proc.returncode == 0, proc.stderr
    return out.read_bytes()


def test_every_asset_is_baked_and_equals_a_local_bake(
    first_run: FirstRun, batch: Batch, hce_bin: str, tmp_path: Path
) -> None:
    good = [r for r in first_run.result.results if r.asset.input != batch.damaged]
    assert len(good) >= 20
    assert all(r.status in ("baked", "cached") for r in good), [r.to_json() for r in good]
    assert first_run.result.bakes == len({r.key for r in good})
    # Local bakes with all cores against the workers' one thread each: the same bytes.
    with ThreadPoolExecutor(max_workers=2) as pool:
        local = list(
            pool.map(
                lambda ir: _local_bake(hce_bin, ir[1].asset.input, tmp_path / f"{ir[0]}.glb"),
                enumerate(good),
            )
        )
    for r, expected in zip(good, local):
        assert r.asset.output.read_bytes() == expected, r.asset.input
        assert r.key is not None
        assert Path(batch.store.path(r.key, "glb")).read_bytes() == expected


def test_a_killed_worker_loses_nothing_and_bakes_nothing_twice(
    first_run: FirstRun, batch: Batch
) -> None:
    killed = first_run.killed
    assert killed is not None, "no bake was seen to kill its worker"
    # The killed worker's hce did not go on unattended.
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            if psutil.Process(killed["hce_pid"]).status() == psutil.STATUS_ZOMBIE:
                break
        except psutil.NoSuchProcess:
            break
        time.sleep(0.1)
    else:
        pytest.fail(f"the bake of the killed worker is still running: {killed}")
    results = {str(r.asset.input): r for r in first_run.result.results}
    victim = results[killed["input"]]
    assert victim.status == "baked", victim.to_json()
    assert victim.worker is not None and not victim.worker.endswith(f":{killed['worker_pid']}")
    for r in first_run.result.results:
        if r.key is not None and r.status != "failed":
            records = batch.store.records(r.key)
            assert len(records) == 1, (r.asset.input, records)
    stray = [p for p in Path(batch.store.root).rglob("*") if p.name.endswith(".tmp")]
    assert stray == []


def test_the_damaged_asset_fails_alone_with_hces_status_and_message(
    first_run: FirstRun, batch: Batch
) -> None:
    failed = [r for r in first_run.result.results if r.status == "failed"]
    assert [r.asset.input for r in failed] == [batch.damaged]
    assert failed[0].exit_status == 3
    assert failed[0].error is not None and "broken.glb" in failed[0].error
    assert not failed[0].asset.output.exists()


def test_a_rerun_bakes_nothing_and_says_so(
    first_run: FirstRun, batch: Batch, cluster: distributed.LocalCluster, hce_bin: str
) -> None:
    records_before = sorted(p.name for p in Path(batch.store.root, "log").rglob("*.json"))
    report = batch.root / "rerun.json"
    code = cli_main(
        [
            str(batch.root / "batch.toml"),
            "--hce",
            hce_bin,
            "--scheduler",
            cluster.scheduler_address,
            "--bake-threads",
            "1",
            "--timeout",
            str(BAKE_TIMEOUT),
            "--batch-timeout",
            str(BATCH_TIMEOUT),
            "--report",
            str(report),
        ]
    )
    # The damaged asset is tried again and fails again; the exit status says a bake failed.
    assert code == 1
    summary = json.loads(report.read_text())
    assert summary["baked"] == 0
    assert summary["bakes"] == 0
    assert summary["cached"] == len(first_run.result.results) - 1
    assert summary["failed"] == 1
    failed = [r for r in summary["results"] if r["status"] == "failed"]
    assert failed[0]["exit_status"] == 3 and "broken.glb" in failed[0]["error"]
    records_after = sorted(p.name for p in Path(batch.store.root, "log").rglob("*.json"))
    assert records_after == records_before


def test_inputs_shipped_to_the_workers_bake_as_in_place(
    client: distributed.Client, hce_bin: str, tmp_path: Path
) -> None:
    # A .gltf whose buffer sits in a sibling folder: the worker lays it out under its own
    # temporary folder, and the key (checked by the worker against its bake's) is the same.
    glb = (REPO / "samples" / "cornell-box.glb").read_bytes()
    json_len = int.from_bytes(glb[12:16], "little")
    doc = json.loads(glb[20 : 20 + json_len])
    bin_len = int.from_bytes(glb[20 + json_len : 24 + json_len], "little")
    (tmp_path / "buffers").mkdir()
    (tmp_path / "buffers" / "box.bin").write_bytes(glb[28 + json_len : 28 + json_len + bin_len])
    doc["buffers"][0]["uri"] = "../buffers/box.bin"
    (tmp_path / "scenes").mkdir()
    scene = tmp_path / "scenes" / "box.gltf"
    scene.write_text(json.dumps(doc))
    (tmp_path / "ship.toml").write_text(
        f'[[bake]]\nfiles = "scenes/*.gltf"\noutput = "out/{{stem}}.glb"\n'
        f"[bake.params]\n{_toml_params()}\n"
    )
    result = run_batch(
        load_manifest(tmp_path / "ship.toml"),
        client,
        hce=hce_bin,
        store=Store(str(tmp_path / "store")),
        bake_threads=1,
        timeout=BAKE_TIMEOUT,
        batch_timeout=BATCH_TIMEOUT,
        ship_inputs=True,
        stream=io.StringIO(),
    )
    assert [r.status for r in result.results] == ["baked"], result.to_json()
    expected = _local_bake(hce_bin, scene, tmp_path / "local.glb")
    assert (tmp_path / "out" / "box.glb").read_bytes() == expected
    assert os.listdir(tmp_path / "out") == ["box.glb"]
