"""The `hce` and `gen-samples` binaries the cluster tests drive."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def hce_bin() -> str:
    """`$HCE_BIN`: CI builds `target/debug/hce` and points it there."""
    path = os.environ.get("HCE_BIN")
    if not path or not os.access(path, os.X_OK):
        pytest.fail(
            f"HCE_BIN={path!r} is not an executable; build hce (cargo build -p hce-tools) and "
            "set HCE_BIN=$PWD/target/debug/hce"
        )
    return path


@pytest.fixture(scope="session")
def gen_samples(hce_bin: str) -> str:
    """`$HCE_GEN_SAMPLES`, else the `gen-samples` built beside `hce`."""
    path = os.environ.get("HCE_GEN_SAMPLES") or str(Path(hce_bin).with_name("gen-samples"))
    if not os.access(path, os.X_OK):
        found = shutil.which("gen-samples")
        if found is None:
            pytest.fail(
                f"{path} is not an executable; build it (cargo build -p hce-samples) or set "
                "HCE_GEN_SAMPLES"
            )
        path = found
    return path
