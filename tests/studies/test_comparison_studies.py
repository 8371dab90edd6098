"""The comparison studies run each configuration in its own process on Dask.

Reference: a configuration run in its own process gives the same summary as
the same scene run here (same code, same numbers to round-off); a rerun starts
nothing unless the library source changed; a failing configuration is reported
with its log.  The demos built on
it are tested in ``tests/baseline/test_demos.py``.
"""

from __future__ import annotations

import pytest
from _study import run_cases

from skfem_npfem.scenes import run_scene

pytest.importorskip("distributed", reason="needs the sweep extra (Dask)")


def test_each_case_in_its_own_process_on_dask(tmp_path):
    params = {"spacing": 0.5, "method": "fem-remap", "element": "p2", "nu": 0.25}
    cases = {"p2": ("elastic-column", params)}
    first = run_cases(cases, tmp_path, workers=1, progress=False)["p2"]
    here = run_scene("elastic-column", params)
    for key in ("sigma_v_rel_l2", "settlement", "base_sigma_v"):
        assert first["metrics"][key] == pytest.approx(here["metrics"][key], rel=1e-12)
    assert first["solver"]["peak_memory_mb"] > 0
    assert (tmp_path / "p2" / "result.pvd").is_file()
    # A rerun finds the finished summary and starts nothing.
    stamp = (tmp_path / "p2" / "summary.json").stat().st_mtime_ns
    again = run_cases(cases, tmp_path, workers=1, progress=False)["p2"]
    assert again == first
    assert (tmp_path / "p2" / "summary.json").stat().st_mtime_ns == stamp
    # A run made by another library source is not reused: it runs again.
    source = tmp_path / "p2" / "source.txt"
    sha = source.read_text()
    source.write_text("0123456789ab")
    fresh = run_cases(cases, tmp_path, workers=0, progress=False)["p2"]
    assert fresh["metrics"] == first["metrics"] and source.read_text() == sha
    assert (tmp_path / "p2" / "summary.json").stat().st_mtime_ns != stamp
    # A failing case is reported as None with its log.
    bad = run_cases(
        {"bad": ("elastic-column", {"method": "spfem"})},
        tmp_path,
        workers=1,
        progress=False,
    )
    assert bad["bad"] is None
    assert "spfem" in (tmp_path / "bad" / "log.txt").read_text()
