"""``column-collapse --set geometry=...``: the four geometries from the CLI, bad
input, and the stress roughness against its definition.

References: mass conservation (exact), the volume of the lattice body (the
full ring pi r0^2 h0 in axisymmetry, L0 H0 W for the box), lattice counts by
enumeration, Lube et al. 2004's law, and an independent implementation of the
stress-roughness definition (``tests/roughness_reference.py``).
"""

from __future__ import annotations

import json
import math

import meshio
import numpy as np
import pytest
from roughness_reference import reference_roughness
from skfem import MeshTet, MeshTri

import skfem_npfem as npfem
from skfem_npfem.cli import main
from skfem_npfem.laws import lube2004_runout
from skfem_npfem.metrics import roughness_index
from skfem_npfem.scenes import get_scene
from skfem_npfem.scenes.collapse.runs import bare_method
from skfem_npfem.scenes.collapse.sizing import lattice_particles
from skfem_npfem.viz.scenery import scenery

R0, H0, RHO = 0.039, 0.078, 1800.0


def run_cli(tmp_path, name, *sets):
    out, summ = tmp_path / name, tmp_path / f"{name}.json"
    argv = ["run", "column-collapse", "--quiet", "--out", str(out)]
    argv += ["--summary", str(summ)]
    for s in sets:
        argv += ["--set", s]
    assert main(argv) == 0
    return json.loads(summ.read_text()), out


def quarter_count(n_r: int, n_z: int) -> int:
    """Lattice points (i, j, k) with i^2 + j^2 <= n_r^2, by enumeration."""
    per = sum(
        1 for i in range(n_r + 1) for j in range(n_r + 1) if i * i + j * j <= n_r**2
    )
    return per * (n_z + 1)


# The four geometries, a few steps each (~15 s together).  Spacing r0/6 for the
# cylinders (7 x 13 half-section, 455 particles in the quarter); the box at
# spacing L0/5 with the default depth (4 spacings).
CASES = {
    "plane-strain": (["spacing=0.04", "t_end=0.02"], 6 * 11),
    "axisymmetric": ([f"spacing={R0 / 6}", "t_end=0.012"], 7 * 13),
    # (the uniform lattice and the seed's fixed step, not the speed defaults)
    "quarter-cylinder": (
        [f"spacing={R0 / 6}", "t_end=0.006", "refine=none", "dt=0.002"],
        quarter_count(6, 12),
    ),
    "box": (["spacing=0.04", "t_end=0.015"], 6 * 5 * 11),
}


@pytest.mark.parametrize("geometry", list(CASES))
def test_geometry_runs_from_the_cli(tmp_path, geometry):
    sets, n_expected = CASES[geometry]
    summ, out = run_cli(tmp_path, geometry, f"geometry={geometry}", *sets)
    m, hist = summ["metrics"], summ["history"]
    dt = summ["parameters"]["dt"]
    assert m["n_particles"] == n_expected
    assert all(h["status"] == "Solved" and h["retries"] == 0 for h in hist)
    assert len(hist) == round(summ["parameters"]["t_end"] / dt)
    assert m["mass_change"] == 0.0  # particle masses: exact
    mass = hist[0]["mass"]
    if geometry == "axisymmetric":
        # Full-ring masses of the lattice rectangle: rho pi r0^2 h0 (1e-12).
        assert abs(mass / (RHO * math.pi * R0**2 * H0) - 1) < 1e-12
        assert m["reference_runout_lube2004"] == pytest.approx(1.6 * math.sqrt(2))
        # The pictures' scenery: the (r, z) section, the axis, Lube et al. 2004.
        sc = scenery(out)
        assert np.allclose(sc.outline.max(axis=0), [R0, H0])
        assert sc.runout_reference == pytest.approx(R0 * (1 + 1.6 * math.sqrt(2)))
        assert "2004" in sc.runout_label and not sc.walls  # the axis is no wall
        assert sc.symmetry == 0.0 and sc.symmetry_label.startswith("axis")
        assert sc.axes == ("r", "z") and "hoop" in sc.field_names["stress_zz"]
    if geometry == "box":
        # The slab: rho L0 H0 W (1e-12), W = 4 spacings.
        assert abs(mass / (RHO * 0.2 * 0.4 * 0.16) - 1) < 1e-12
        assert summ["parameters"]["dp_match"] == "plane-strain"
    if geometry in ("axisymmetric", "quarter-cylinder"):
        assert summ["parameters"]["dt"] == 2e-3  # the seed's time step
        # The column has started to fall, the front has not yet moved far.
        assert R0 <= m["runout_radius"] < 1.2 * R0
        # The history's per-step front (docs/output.md) ends at the metric.
        assert hist[-1]["runout_radius"] == pytest.approx(m["runout_radius"])
        assert 0.9 < m["height_ratio"] < 1.0
    # No particle below the floor; the last VTU is the last step.
    last = meshio.read(sorted(out.glob("result_*.vtu"))[-1])
    assert last.points[:, -1 if geometry != "axisymmetric" else 1].min() >= -1e-12
    if geometry != "plane-strain":
        assert m["mass_basis"]


# -------------------------------------------------------------- bad input ----
@pytest.mark.parametrize(
    ("sets", "name"),
    [
        (["geometry=axisymmetric", "radius=0.05", "height=0.1", "aspect=2"], "aspect"),
        (["geometry=quarter-cylinder", "symmetric=false"], "symmetric"),
        (["geometry=axisymmetric", "half_width=0.1"], "half_width"),
        (["geometry=plane-strain", "radius=0.05"], "radius"),
        (["height=0.05"], "height"),
        (["geometry=box", "height=0.1"], "height"),
        (["geometry=axisymmetric", "depth=0.1"], "depth"),
        (["geometry=axisymmetric", f"spacing={R0 / 3.9}"], "spacing"),
        (["geometry=quarter-cylinder", "material=mohr-coulomb"], "material"),
        (["geometry=axisymmetric", "max_displacement=0.5"], "max_displacement"),
        (["geometry=axisymmetric", "method=fem-remap"], "method"),
        (["geometry=box", "element=p2"], "element"),
        (["geometry=axisymmetric", "material=mohr-coulomb", "dp_match=compression"],
         "dp_match"),
        (["geometry=quarter-cylinder", "spacing=1e-5"], "spacing"),
        (["geometry=box", "spacing=1e-5"], "spacing"),
    ],
)  # fmt: skip
def test_bad_geometry_input_is_one_error_line_before_any_work(
    tmp_path, capsys, sets, name
):
    out = tmp_path / "never"
    argv = ["run", "column-collapse", "--quiet", "--out", str(out)]
    for s in sets:
        argv += ["--set", s]
    assert main(argv) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: invalid {name}="), err
    assert not out.exists()  # refused before anything was written


def test_memory_refusal_says_estimate_machine_and_fix(capsys):
    code = main(
        ["run", "column-collapse", "--quiet", "--set", "geometry=quarter-cylinder",
         "--set", "spacing=1e-4"]
    )  # fmt: skip
    assert code == 2
    err = capsys.readouterr().err
    # ~(pi/4) 390^2 x 781 = 9.3e7 particles (the smallest spacing, 1e-4 m):
    # far beyond any machine.
    for word in ("9.36e+07 particles", "memory", "size_check=false"):
        assert word in err, word


def test_particle_estimate_is_the_lattice_count():
    # Exact for the rectangles, within 3 % of the enumerated quarter-cylinder
    # lattice (r0/18: 10 027 particles) -- the count the size check uses.
    v = {"radius": R0, "height": H0}
    assert lattice_particles("axisymmetric", v, R0 / 18) == 19 * 37
    n = lattice_particles("quarter-cylinder", v, R0 / 18)
    assert abs(n / quarter_count(18, 36) - 1) < 0.03
    box = {"half_width": 0.2, "aspect": 2.0, "depth": 0.16, "symmetric": True}
    assert lattice_particles("box", box, 0.04) == 6 * 5 * 11


def test_geometry_defaults_are_the_seed_case():
    scene = get_scene("column-collapse")
    v = scene.resolve({"geometry": "quarter-cylinder"})
    assert (v["radius"], v["height"], v["aspect"]) == (R0, H0, 2.0)
    assert v["spacing"] == R0 / 18
    assert (v["material"], v["dp_match"]) == ("drucker-prager", "compression")
    # The quarter's speed defaults (docs/performance.md): the graded lattice,
    # the fast preset, steps of up to 6 ms within one spacing of motion ...
    assert (v["refine"], v["accuracy"]) == ("surface", "fast")
    assert (v["dt"], v["max_displacement"]) == (6e-3, 1.0)
    # ... each off where the user chose: a dt given alone is a fixed step, a
    # tol keeps its tolerance, a max_displacement keeps the 6 ms cap.
    w = scene.resolve({"geometry": "quarter-cylinder", "dt": 4e-3, "tol": 1e-7})
    assert (w["dt"], w["max_displacement"], w["accuracy"]) == (4e-3, None, None)
    w = scene.resolve({"geometry": "quarter-cylinder", "max_displacement": 0.5})
    assert (w["dt"], w["max_displacement"]) == (6e-3, 0.5)
    w = scene.resolve(
        {"geometry": "quarter-cylinder", **bare_method("quarter-cylinder")}
    )
    assert (w["refine"], w["tol"], w["accuracy"]) == ("none", 1e-8, None)
    assert (w["dt"], w["max_displacement"]) == (2e-3, None)
    # The axisymmetric section keeps the seed's fixed 2 ms and uniform lattice.
    w = scene.resolve({"geometry": "axisymmetric"})
    assert (w["dt"], w["max_displacement"], w["refine"]) == (2e-3, None, "none")
    # The 3D quarter's alpha shape: 2.0 (docs/seed_column.md, "Where the 3D
    # volume goes"); the sections keep 1.3, and a given alpha is kept.
    assert v["alpha"] == 2.0
    assert scene.resolve({"geometry": "axisymmetric"})["alpha"] == 1.3
    assert scene.resolve({"geometry": "box"})["alpha"] == 1.3
    assert scene.resolve({"geometry": "quarter-cylinder", "alpha": 1.3})["alpha"] == 1.3
    v = scene.resolve({"geometry": "axisymmetric", "radius": 0.05, "aspect": 1.5})
    assert v["height"] == pytest.approx(0.075, rel=1e-15)
    v = scene.resolve({"geometry": "axisymmetric", "height": 0.1})
    assert v["radius"] == pytest.approx(0.05, rel=1e-15)
    # Plane strain keeps its own defaults (unchanged).
    v = scene.resolve({})
    assert v["dt"] == 5e-3 and v["material"] == "mohr-coulomb" and v["radius"] is None
    assert v["alpha"] == 1.3


def test_lube_2004_law():
    # (r_inf - r0)/r0 = 1.24 a for a <= 1.7, 1.6 a^(1/2) above.
    assert lube2004_runout(1.0) == pytest.approx(1.24)
    assert lube2004_runout(4.0) == pytest.approx(3.2)
    assert abs(lube2004_runout(1.7) / lube2004_runout(1.7001) - 1) < 0.011


# -------------------------------------------------------- roughness ----
def test_roughness_of_linear_fields_and_a_checkerboard():
    # Linear field on a regular lattice: every interior particle equals its
    # neighbours' mean, R = 0 (1e-12).  Checkerboard (-1)^(i+j) on the
    # structured triangulation: 4 of the 6 neighbours have the opposite sign,
    # the mean is -1/3 s_i and R = 4/3 exactly.
    m = MeshTri.init_tensor(np.linspace(0, 1, 12), np.linspace(0, 2, 15))
    r, n = roughness_index(m.t.T, 3.0 + m.p[0] - 2.0 * m.p[1])
    assert n == (12 - 4) * (15 - 4) and r < 1e-12
    i = np.rint(m.p[0] * 11).astype(int) + np.rint(m.p[1] * 7).astype(int)
    r, _ = roughness_index(m.t.T, (-1.0) ** i)
    assert abs(r - 4 / 3) < 1e-12
    m3 = MeshTet.init_tensor(*[np.linspace(0, 1, 7)] * 3)
    r, n = roughness_index(m3.t.T, 1.0 + m3.p.sum(axis=0))
    assert n == 3**3 and r < 1e-12


@pytest.mark.parametrize("geometry", ["axisymmetric", "quarter-cylinder"])
def test_roughness_equals_the_reference_measure(tmp_path, geometry):
    # The per-step stress_roughness of the run equals the independent
    # implementation of the definition on every written VTU (1e-12 relative;
    # NaN where both find fewer than 10 interior particles), as do the public
    # npfem.stress_roughness on the file; the summary's stress_roughness is the
    # last step's.
    spacing = R0 / 8
    summ, out = run_cli(
        tmp_path, geometry, f"geometry={geometry}", f"spacing={spacing}",
        "t_end=0.006", "output_every=1",
    )  # fmt: skip
    per_step = {h["step"]: h["stress_roughness"] for h in summ["history"]}
    compared = 0
    for f in sorted(out.glob("result_*.vtu"))[1:]:  # step 0: no solved step
        step = int(f.stem.split("_")[1])
        m = meshio.read(f)
        cells = np.vstack([c.data for c in m.cells if c.type in ("triangle", "tetra")])
        dim = cells.shape[1] - 1
        stress = m.point_data["stress"]
        ref, _ = reference_roughness(cells, stress[:, dim - 1])
        ours = per_step[step]
        public = npfem.stress_roughness(cells, stress)
        if ours is None or not math.isfinite(ref):
            assert ours is None and not math.isfinite(public)
            assert not math.isfinite(ref)
            continue
        assert public == ours
        assert abs(ours - ref) <= 1e-12 * ref
        compared += 1
    # 3D: the second step's mesh has ~2 800 internal facets where zero-volume
    # slivers of the (still nearly cubic) lattice were dropped, and no
    # interior particle by the definition (scene and reference both give NaN).
    assert compared >= (1 if geometry == "quarter-cylinder" else 2)
    last = summ["history"][-1]["stress_roughness"]
    assert summ["metrics"]["stress_roughness"] == last
