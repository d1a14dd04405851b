"""Bake many assets with `hce bake` on a Dask cluster.

Each asset's bake is keyed by `hce bake --print-key` (a SHA-256 over its input files' bytes, its
canonical parameters and the hce version), and its output is kept in a content-addressed store
under that key, so a rerun bakes only what changed. See the README's "Baking many assets".
"""

from hce_batch.manifest import Asset, Manifest, ManifestError, load_manifest
from hce_batch.runner import BatchResult, run_batch
from hce_batch.store import Store

__all__ = [
    "Asset",
    "BatchResult",
    "Manifest",
    "ManifestError",
    "Store",
    "load_manifest",
    "run_batch",
]
