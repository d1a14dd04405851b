"""What a Dask worker runs for one asset: `hce bake` into a private temporary folder, then the
output into the store under its key.

A task never leaves a partial output: hce writes into the temporary folder, and the store takes
the file whole. A bake that fails (damaged input, bad flag) is a result, not an exception, so
that it is reported with hce's exit status and message and not retried; only a task whose
worker dies (or that raises) is run again, and then it first looks whether an earlier run
already stored its key.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hce_batch.store import Store


@dataclass(frozen=True)
class BakeSpec:
    """Everything a worker needs for one bake."""

    hce: str
    input: str
    args: tuple[str, ...]
    key: str
    format: str
    store: str
    #: `--threads` for hce (`None`: all the worker machine's cores).
    threads: int | None = None
    #: Seconds before the bake is stopped and reported failed.
    timeout: float = 3600.0
    #: The asset's files by name within the asset (`scene.glb`, `textures/wood.png`), when the
    #: client ships them to workers that cannot read its paths; empty to read `input` in place.
    files: tuple[tuple[str, bytes], ...] = field(default=())


def _die_with_parent() -> None:
    """Runs in the forked child before hce starts: if the worker process dies (killed, lost),
    the kernel ends its bake too instead of leaving it running unattended."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGKILL)
    except (OSError, AttributeError):
        pass


def _lay_out(files: tuple[tuple[str, bytes], ...], root: Path) -> Path:
    """Writes shipped files under `root` with their names within the asset, deep enough that
    `..` in a name stays inside, and returns the scene file's path."""
    depth = max((n.split("/").count("..") for n, _ in files), default=0)
    scene_dir = root.joinpath(*(["d"] * depth))
    scene: Path | None = None
    for name, data in files:
        if name.startswith("/"):
            raise ValueError(f"{name}: an absolute path cannot be shipped to a worker")
        target = (scene_dir / name).resolve()
        if not target.is_relative_to(root.resolve()):
            raise ValueError(f"{name}: leaves the asset's folder")
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)
        if name.startswith("scene.") and "/" not in name:
            scene = target
    if scene is None:
        raise ValueError("the shipped files hold no scene file")
    return scene


def bake(spec: BakeSpec) -> dict[str, Any]:
    """Bakes one asset into the store (see the module documentation). Returns a result with
    `status` `baked`, `cached` (already stored) or `failed`, and hce's `exit_status` and
    `error` when it failed."""
    store = Store(spec.store)
    worker = f"{socket.gethostname()}:{os.getpid()}"
    base: dict[str, Any] = {"key": spec.key, "worker": worker}
    if store.exists(spec.key, spec.format):
        return {**base, "status": "cached", "seconds": 0.0}
    started = time.monotonic()
    tmp = Path(tempfile.mkdtemp(prefix="hce-batch-"))
    try:
        scene = _lay_out(spec.files, tmp / "asset") if spec.files else Path(spec.input)
        out = tmp / f"out.{spec.format}"
        report_path = tmp / "report.json"
        cmd = [spec.hce, "bake", str(scene), "-o", str(out), "--report", str(report_path), "-q"]
        if spec.threads is not None:
            cmd += ["--threads", str(spec.threads)]
        cmd += list(spec.args)
        try:
            proc = subprocess.run(
                cmd,
                capture_output=True,
                text=True,
                timeout=spec.timeout,
                preexec_fn=_die_with_parent,
                check=False,
            )
        except subprocess.TimeoutExpired:
            return {
                **base,
                "status": "failed",
                "exit_status": None,
                "error": f"hce bake ran past the timeout of {spec.timeout:g} s and was stopped",
                "seconds": time.monotonic() - started,
            }
        except OSError as e:
            return {
                **base,
                "status": "failed",
                "exit_status": None,
                "error": f"cannot run {spec.hce}: {e}",
                "seconds": time.monotonic() - started,
            }
        report: dict[str, Any] | None = None
        if report_path.is_file():
            report = json.loads(report_path.read_text(encoding="utf-8"))
        seconds = time.monotonic() - started
        if proc.returncode != 0:
            message = (report or {}).get("error") or proc.stderr.strip() or "no message"
            return {
                **base,
                "status": "failed",
                "exit_status": proc.returncode,
                "error": message,
                "seconds": seconds,
                "report": report,
            }
        if report is None or report.get("key") != spec.key:
            got = None if report is None else report.get("key")
            return {
                **base,
                "status": "failed",
                "exit_status": proc.returncode,
                "error": f"the bake's key {got} is not the key {spec.key} it was submitted "
                "under: its inputs changed in between",
                "seconds": seconds,
                "report": report,
            }
        if not store.put(spec.key, spec.format, out):
            return {**base, "status": "cached", "seconds": seconds}
        store.record(
            spec.key,
            {"worker": worker, "seconds": seconds, "time": time.time(), "report": report},
        )
        return {**base, "status": "baked", "seconds": seconds, "report": report}
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
