"""A digest of short runs: every number the library writes, hashed per case.

A change that should not change any result (moving modules, renaming, tidying)
is checked by running this script before and after it: the digests must be
identical to the last bit.  Each case is a short run of a scene through
:func:`skfem_npfem.run_scene` into a folder; its digest hashes

* the summary's metrics and the step records (statuses, iteration counts,
  energies, body loads), without wall times and memory, which vary;
* every array of every VTU file the run wrote (points, cells, point data);
* every array of the checkpoints (their JSON records without timings).

The cases cover the six scenes, the four column geometries (plane strain,
axisymmetric, 3D quarter cylinder, 3D box), the three methods (N-PFEM,
FEM-remap, SPFEM), rigid bodies in plane strain and axisymmetry, and limit
analysis with and without strength reduction.  Every run uses one solver thread.

The digests are one machine's: another CPU rounds some runs differently in the
last bits (seen on a new machine: 9 of the 16 cases matched
``benchmarks/results/digest.json``, with the code it was written with as with
later code that changed nothing), so compare two runs made on the same machine,
before and after the change, rather than a run with the committed file.

Usage::

    python benchmarks/digest.py --out digest.json          # all cases
    python benchmarks/digest.py --compare digest.json      # rerun and compare

``--compare`` exits 1 and names the cases whose digest changed.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
import warnings
from pathlib import Path

import meshio
import numpy as np

import skfem_npfem as npfem
from skfem_npfem.scenes.collapse.geometry import QUARTER_FIXED

#: name -> (scene, overrides): short runs, a few seconds each.
CASES: dict[str, tuple[str, dict]] = {
    "collapse-plane": ("column-collapse", {"spacing": 0.05, "t_end": 0.03}),
    "collapse-plane-fem-remap": (
        "column-collapse",
        {"spacing": 0.05, "t_end": 0.03, "method": "fem-remap"},
    ),
    "collapse-plane-spfem": (
        "column-collapse",
        {"spacing": 0.05, "t_end": 0.01, "method": "spfem"},
    ),
    "collapse-axisymmetric": (
        "column-collapse",
        {"geometry": "axisymmetric", "spacing": 0.0078, "t_end": 0.008},
    ),
    # (the uniform lattice and the fixed 2 ms it was first recorded with)
    "collapse-quarter-cylinder": (
        "column-collapse",
        {
            "geometry": "quarter-cylinder",
            "spacing": 0.00975,
            "t_end": 0.006,
            **QUARTER_FIXED,
        },
    ),
    "collapse-quarter-cylinder-speed": (
        "column-collapse",
        {"geometry": "quarter-cylinder", "spacing": 0.00975, "t_end": 0.012},
    ),
    "collapse-box": (
        "column-collapse",
        {"geometry": "box", "spacing": 0.05, "t_end": 0.01},
    ),
    "elastic-column-3d": ("elastic-column", {"dim": 3, "spacing": 0.5}),
    "elastic-column-dynamic-spfem": (
        "elastic-column",
        {"spacing": 0.5, "mode": "dynamic", "steps": 3, "method": "spfem"},
    ),
    "strip-footing": ("strip-footing", {"spacing": 0.25, "steps": 3, "max_steps": 4}),
    "strip-footing-fem-remap": (
        "strip-footing",
        {"spacing": 0.25, "steps": 3, "max_steps": 4, "method": "fem-remap"},
    ),
    "strip-footing-limit": (
        "strip-footing",
        {"analysis": "limit", "refine": "none", "spacing": 0.25, "domain_width": 5},
    ),
    "slope-limit": ("slope", {"analysis": "limit", "refine": "none", "spacing": 2.0}),
    "slope-runout": (
        "slope",
        {"spacing": 2.0, "runout": "true", "t_end": 0.5, "phi": 10.0},
    ),
    "footing-penetration": (
        "footing-penetration",
        {"spacing": 0.25, "penetration": 0.2, "domain_width": 4, "domain_depth": 2},
    ),
    "cone-penetration": (
        "cone-penetration",
        {"spacing": 0.0357 / 4, "penetration": 0.02},
    ),
}

#: Summary keys that measure the machine, not the method.
_MACHINE = ("wall", "memory", "time_median", "step_time", "seconds", "timings")


def _numbers_only(value):
    """``value`` without the entries that measure the machine."""
    if isinstance(value, dict):
        return {
            k: _numbers_only(v)
            for k, v in sorted(value.items())
            if not any(m in k for m in _MACHINE)
        }
    if isinstance(value, list):
        return [_numbers_only(v) for v in value]
    return value


def _hash_array(h, name: str, a) -> None:
    a = np.ascontiguousarray(np.asarray(a))
    h.update(f"{name}:{a.dtype.str}:{a.shape}".encode())
    h.update(a.tobytes())


def case_digest(folder: Path, summary: dict) -> str:
    """The digest of one run: its summary's numbers and every array it wrote."""
    h = hashlib.sha256()
    kept = {k: summary.get(k) for k in ("metrics", "solver", "history")}
    h.update(json.dumps(_numbers_only(kept), sort_keys=True, default=repr).encode())
    for vtu in sorted(folder.glob("*.vtu")):
        mesh = meshio.read(vtu)
        _hash_array(h, f"{vtu.name}/points", mesh.points)
        for block in mesh.cells:
            _hash_array(h, f"{vtu.name}/{block.type}", block.data)
        for key in sorted(mesh.point_data):
            _hash_array(h, f"{vtu.name}/{key}", mesh.point_data[key])
    for npz in sorted(folder.glob("*.npz")):
        with np.load(npz, allow_pickle=False) as data:
            for key in sorted(data.files):
                if key == "__meta__":  # JSON: the run's records, with timings
                    meta = _numbers_only(json.loads(str(data[key])))
                    h.update(json.dumps(meta, sort_keys=True).encode())
                else:
                    _hash_array(h, f"{npz.name}/{key}", data[key])
    return h.hexdigest()


def run_cases(names: list[str]) -> dict[str, str]:
    """Run the named cases, each into a fresh folder, and digest them."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            scene, overrides = CASES[name]
            folder = Path(tmp) / name
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                summary = npfem.run_scene(
                    scene, {**overrides, "threads": 1}, out=folder
                )
            out[name] = case_digest(folder, summary)
            print(f"{name:30s} {out[name][:16]}", flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, help="write the digests to this JSON")
    parser.add_argument("--compare", type=Path, help="compare with this JSON")
    parser.add_argument("--cases", nargs="*", default=list(CASES), choices=CASES)
    args = parser.parse_args(argv)
    digests = run_cases(args.cases)
    if args.out:
        args.out.write_text(json.dumps(digests, indent=1) + "\n")
    if args.compare:
        before = json.loads(args.compare.read_text())
        changed = [k for k in digests if before.get(k) != digests[k]]
        for name in changed:
            print(f"changed: {name}")
        print(f"{len(digests) - len(changed)} of {len(digests)} cases bit-identical")
        return 1 if changed else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
