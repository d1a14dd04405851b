"""`hce-batch MANIFEST`: bake a manifest's assets on a Dask cluster, cached by bake key.

Exit status: 0 when every asset is baked or cached, 1 when any failed (the report says which,
with hce's exit status and message), 2 for a bad command line or manifest.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
from pathlib import Path

from hce_batch.manifest import ManifestError, load_manifest
from hce_batch.runner import run_batch
from hce_batch.store import Store


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="hce-batch",
        description="Bake the assets a manifest names with `hce bake` on a Dask cluster; "
        "outputs are kept in a content-addressed store under each bake's key "
        "(`hce bake --print-key`), so a rerun bakes only what changed.",
        epilog="Exit status: 0 all assets baked or cached, 1 some failed, 2 usage error.",
    )
    p.add_argument("manifest", type=Path, help="TOML or JSON manifest (see the README)")
    p.add_argument(
        "--store",
        help="store folder or fsspec URL (default: the manifest's `store`, else "
        "`hce-store` beside the manifest)",
    )
    p.add_argument(
        "--hce",
        default=os.environ.get("HCE_BIN", "hce"),
        help="the hce binary, as the workers find it (default: $HCE_BIN, else hce on PATH)",
    )
    p.add_argument(
        "--scheduler",
        help="address of a running scheduler (tcp://host:port); default: a local cluster",
    )
    p.add_argument(
        "--workers", type=int, default=2, help="worker processes of the local cluster (default 2)"
    )
    p.add_argument(
        "--bake-threads",
        type=int,
        help="`hce bake --threads` for each bake (default: all of a worker machine's cores)",
    )
    p.add_argument(
        "--retries", type=int, default=2, help="tries again for a task that raises (default 2)"
    )
    p.add_argument(
        "--timeout",
        type=float,
        default=3600.0,
        help="seconds one bake may take before it is stopped and failed (default 3600)",
    )
    p.add_argument(
        "--batch-timeout",
        type=float,
        help="seconds the whole batch may take; unfinished bakes then fail",
    )
    p.add_argument(
        "--ship-inputs",
        action="store_true",
        help="send each asset's files to the workers with the task (workers that cannot "
        "read the client's paths); by default workers read the input paths",
    )
    p.add_argument(
        "--link",
        choices=["auto", "hard", "symlink", "copy"],
        default="auto",
        help="how destinations are made from the store (default: a hard link where possible, "
        "else a copy)",
    )
    p.add_argument("--report", type=Path, help="write the batch report (JSON) here")
    return p


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    if args.workers < 1:
        print("hce-batch: error: --workers needs at least 1", file=sys.stderr)
        return 2
    try:
        manifest = load_manifest(args.manifest)
    except ManifestError as e:
        print(f"hce-batch: error: {e}", file=sys.stderr)
        return 2
    if shutil.which(args.hce) is None and args.scheduler is None:
        print(
            f"hce-batch: error: {args.hce} is not an executable; build hce "
            "(cargo build --release -p hce-tools) and pass --hce or set HCE_BIN",
            file=sys.stderr,
        )
        return 2
    store_root = args.store or manifest.store or str(args.manifest.parent / "hce-store")
    store = Store(store_root)

    import distributed

    # distributed's annotations leave these constructors and `close` untyped.
    cluster: distributed.LocalCluster | None = None
    if args.scheduler:
        client = distributed.Client(args.scheduler)  # type: ignore[no-untyped-call]
    else:
        cluster = distributed.LocalCluster(  # type: ignore[no-untyped-call]
            n_workers=args.workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
        )
        client = distributed.Client(cluster)  # type: ignore[no-untyped-call]
    try:
        result = run_batch(
            manifest,
            client,
            hce=args.hce,
            store=store,
            bake_threads=args.bake_threads,
            retries=args.retries,
            timeout=args.timeout,
            batch_timeout=args.batch_timeout,
            ship_inputs=args.ship_inputs,
            link=args.link,
        )
    finally:
        client.close()  # type: ignore[no-untyped-call]
        if cluster is not None:
            cluster.close()
    if args.report:
        result.write(args.report)
    for r in result.results:
        if r.status == "failed":
            status = "" if r.exit_status is None else f" (hce exit status {r.exit_status})"
            print(f"hce-batch: failed: {r.asset.input}{status}: {r.error}", file=sys.stderr)
    print(
        f"hce-batch: {len(result.results)} assets: {result.count('baked')} baked, "
        f"{result.count('cached')} cached, {result.failed} failed in {result.seconds:.1f} s",
        file=sys.stderr,
    )
    return 1 if result.failed else 0


if __name__ == "__main__":
    sys.exit(main())
