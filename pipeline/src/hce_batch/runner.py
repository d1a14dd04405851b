"""The batch: key every asset, bake on the cluster what the store lacks, place the outputs.

1. Each asset's key comes from `hce bake INPUT -o DEST --print-inputs FLAGS`, run where the
   client is (it reads the input files, does not bake).
2. Assets whose key the store holds are done ("cached"). The others are grouped by key (equal
   keys are equal bakes, baked once) and submitted to the Dask client, one task per key, the
   task's Dask key `hce-bake-<key>.<format>`, with `retries` for tasks that raise; the scheduler
   reruns the tasks of a worker it loses.
3. As tasks finish, progress goes to stderr; at the end every asset that has its key stored gets
   its destination (a link into the store or a copy), and the batch report says per asset what
   happened.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import distributed

from hce_batch.manifest import Asset, Manifest
from hce_batch.store import Store
from hce_batch.worker import BakeSpec, bake


@dataclass
class AssetResult:
    asset: Asset
    key: str | None = None
    #: `baked`, `cached` or `failed`.
    status: str = "failed"
    exit_status: int | None = None
    error: str | None = None
    seconds: float = 0.0
    worker: str | None = None
    #: hce's `--report` of the bake, when this batch baked it.
    report: dict[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "input": str(self.asset.input),
            "output": str(self.asset.output),
            "args": list(self.asset.args),
            "key": self.key,
            "status": self.status,
            "exit_status": self.exit_status,
            "error": self.error,
            "seconds": round(self.seconds, 3),
            "worker": self.worker,
            "report": self.report,
        }


@dataclass
class BatchResult:
    results: list[AssetResult]
    seconds: float
    store: str
    #: Distinct keys this batch baked (several assets may share one).
    bakes: int = 0
    notes: list[str] = field(default_factory=list)

    def count(self, status: str) -> int:
        return sum(r.status == status for r in self.results)

    @property
    def failed(self) -> int:
        return self.count("failed")

    def to_json(self) -> dict[str, Any]:
        return {
            "report_format": 1,
            "store": self.store,
            "assets": len(self.results),
            "baked": self.count("baked"),
            "cached": self.count("cached"),
            "failed": self.failed,
            "bakes": self.bakes,
            "seconds": round(self.seconds, 3),
            "notes": self.notes,
            "results": [r.to_json() for r in self.results],
        }

    def write(self, path: Path) -> None:
        """Writes the report atomically."""
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(self.to_json(), indent=1) + "\n", encoding="utf-8")
        os.replace(tmp, path)


def _hce_message(stderr: str) -> str:
    lines = [ln.removeprefix("error: ") for ln in stderr.strip().splitlines()]
    return "; ".join(ln for ln in lines if ln) or "no message"


def key_asset(hce: str, asset: Asset, timeout: float) -> tuple[AssetResult, list[dict[str, Any]]]:
    """The asset's key and input files from `hce bake --print-inputs`."""
    result = AssetResult(asset=asset)
    cmd = [hce, "bake", str(asset.input), "-o", str(asset.output), "--print-inputs"]
    cmd += list(asset.args)
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    except (OSError, subprocess.TimeoutExpired) as e:
        result.error = f"cannot compute the key ({' '.join(cmd)}): {e}"
        return result, []
    if proc.returncode != 0:
        result.exit_status = proc.returncode
        result.error = _hce_message(proc.stderr)
        return result, []
    printed = json.loads(proc.stdout)
    result.key = str(printed["key"])
    inputs: list[dict[str, Any]] = printed["inputs"]
    return result, inputs


class Progress:
    """One line per finished bake on a stream: counts and an estimate of the time left."""

    def __init__(self, total: int, stream: TextIO) -> None:
        self.total = total
        self.stream = stream
        self.started = time.monotonic()
        self.counts = {"baked": 0, "cached": 0, "failed": 0}

    def add(self, status: str, n: int, to_bake: int, baked_keys: int) -> None:
        self.counts[status] += n
        done = sum(self.counts.values())
        left = ""
        elapsed = time.monotonic() - self.started
        if 0 < baked_keys < to_bake:
            seconds = elapsed / baked_keys * (to_bake - baked_keys)
            left = f", about {_duration(seconds)} left"
        elif baked_keys == to_bake:
            left = f", {_duration(elapsed)}"
        self.stream.write(
            f"hce-batch: {done}/{self.total} assets done ({self.counts['baked']} baked, "
            f"{self.counts['cached']} cached, {self.counts['failed']} failed){left}\n"
        )
        self.stream.flush()


def _duration(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 60}m{s % 60:02d}s" if s >= 60 else f"{s}s"


def run_batch(
    manifest: Manifest,
    client: distributed.Client,
    *,
    hce: str,
    store: Store,
    bake_threads: int | None = None,
    retries: int = 2,
    timeout: float = 3600.0,
    batch_timeout: float | None = None,
    ship_inputs: bool = False,
    link: str = "auto",
    stream: TextIO = sys.stderr,
) -> BatchResult:
    """Runs the batch (see the module documentation) and returns its report; never raises for
    an asset's failure."""
    started = time.monotonic()
    assets = list(manifest.assets)
    with ThreadPoolExecutor(max_workers=max(1, os.cpu_count() or 1)) as pool:
        keyed = list(pool.map(lambda a: key_asset(hce, a, timeout), assets))
    results = [r for r, _ in keyed]
    progress = Progress(len(results), stream)
    failed_keys = [r for r in results if r.key is None]
    if failed_keys:
        progress.add("failed", len(failed_keys), 0, 0)

    groups: dict[tuple[str, str], list[int]] = {}
    for i, r in enumerate(results):
        if r.key is not None:
            groups.setdefault((r.key, r.asset.format), []).append(i)
    futures: dict[distributed.Future[dict[str, Any]], tuple[str, str]] = {}
    cached = 0
    for (key, fmt), members in groups.items():
        if store.exists(key, fmt):
            for i in members:
                results[i].status = "cached"
            cached += len(members)
            continue
        first = results[members[0]].asset
        files: tuple[tuple[str, bytes], ...] = ()
        if ship_inputs:
            files = tuple(
                (str(f["name"]), Path(f["path"]).read_bytes())
                for f in keyed[members[0]][1]
                if f["sha256"] is not None
            )
        spec = BakeSpec(
            hce=hce,
            input=str(first.input),
            args=first.args,
            key=key,
            format=fmt,
            store=store.root,
            threads=bake_threads,
            timeout=timeout,
            files=files,
        )
        fut = client.submit(bake, spec, key=f"hce-bake-{key}.{fmt}", retries=retries, pure=False)
        futures[fut] = (key, fmt)
    to_bake = len(futures)
    stream.write(
        f"hce-batch: {len(results)} assets, {len(groups)} distinct bakes; {cached} assets "
        f"cached, {to_bake} bakes submitted\n"
    )
    if cached:
        progress.add("cached", cached, to_bake, 0)

    bakes = 0
    finished = 0
    pending = set(futures)
    deadline = None if batch_timeout is None else started + batch_timeout
    notes: list[str] = []
    while pending:
        wait_for = None if deadline is None else max(0.0, deadline - time.monotonic())
        # distributed's annotations leave `wait` untyped.
        done, pending = distributed.wait(  # type: ignore[no-untyped-call]
            pending, timeout=wait_for, return_when="FIRST_COMPLETED"
        )
        if not done:
            for fut in pending:
                key, fmt = futures[fut]
                fut.cancel()
                for i in groups[(key, fmt)]:
                    results[i].error = f"not finished within the batch timeout of {batch_timeout:g} s"
            notes.append(f"{len(pending)} bakes did not finish within {batch_timeout:g} s")
            progress.add("failed", sum(len(groups[futures[f]]) for f in pending), to_bake, finished)
            break
        for fut in done:
            key, fmt = futures[fut]
            members = groups[(key, fmt)]
            finished += 1
            try:
                outcome: dict[str, Any] = fut.result()
            except Exception as e:  # a task that raised on every try, or lost too many workers
                outcome = {"status": "failed", "exit_status": None, "error": f"{type(e).__name__}: {e}"}
            if outcome["status"] == "baked":
                bakes += 1
            for n, i in enumerate(members):
                r = results[i]
                r.status = outcome["status"]
                r.exit_status = outcome.get("exit_status")
                r.error = outcome.get("error")
                r.seconds = float(outcome.get("seconds", 0.0))
                r.worker = outcome.get("worker")
                # The first asset of a key is the one baked; the others share its output.
                r.report = outcome.get("report") if n == 0 else None
                if r.status == "baked" and n > 0:
                    r.status = "cached"
            progress.add(outcome["status"], 1, to_bake, finished)
            if len(members) > 1:
                shared = "failed" if outcome["status"] == "failed" else "cached"
                progress.add(shared, len(members) - 1, to_bake, finished)

    for r in results:
        if r.status == "failed" or r.key is None:
            continue
        try:
            store.fetch(r.key, r.asset.format, r.asset.output, link=link)
        except OSError as e:
            r.status = "failed"
            r.error = f"cannot place {r.asset.output} from the store: {e}"
    return BatchResult(
        results=results,
        seconds=time.monotonic() - started,
        store=store.root,
        bakes=bakes,
        notes=notes,
    )
