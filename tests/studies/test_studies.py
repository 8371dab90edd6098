"""The two largest studies of demos/studies in reduced form (seconds each).

``collapse_validation.py``: one tiny collapse case run through the study's own
functions (mass conserved exactly; the run-out of a = 1 inside the experimental
band 1.2 a (Lube et al. 2005) to 1.8 a (Lajeunesse et al. 2005)), and the fits
of the committed record reproduced from its rows.  ``speed_accuracy.py``: the
Pareto fronts and the generated page ``docs/choosing.md`` reproduced from the
committed record.  The study modules are on ``sys.path`` (tests/conftest.py).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import collapse_validation
import numpy as np
import pytest
import speed_accuracy

ROOT = Path(__file__).resolve().parents[2]
VALIDATION = ROOT / "docs" / "validation"


def test_collapse_tiny_case_conserves_mass_and_runs_out_in_the_band(tmp_path):
    # a = 1, 6 particles across L0 (49 particles), to rest: about 3 s.
    args = collapse_validation.parser().parse_args(["--threads", "1"])
    params = collapse_validation.case_params(1.0, 6, args)
    path = tmp_path / "a1_N6.json"
    collapse_validation.run_case(1.0, 6, params, path)
    row = collapse_validation.row_from_summary(json.loads(path.read_text()))
    assert row["particles"] == 7 * 7 and row["at_rest"]
    assert row["mass_change"] == 0.0  # particles carry their mass
    # Measured 1.39 (the refined sweep: 1.65 at N = 12).
    assert 1.2 <= row["normalised_runout"] <= 1.8
    assert row["lube"]["value"] == pytest.approx(1.2)
    assert row["lajeunesse"]["value"] == pytest.approx(1.8)


def assert_same_numbers(got, want, rel: float) -> None:
    """``got`` has ``want``'s structure, its floats within ``rel`` of ``want``'s."""
    if isinstance(want, dict):
        assert sorted(got) == sorted(want)
        for key in want:
            assert_same_numbers(got[key], want[key], rel)
    elif isinstance(want, list):
        assert len(got) == len(want)
        for g, w in zip(got, want, strict=True):
            assert_same_numbers(g, w, rel)
    elif isinstance(want, float):
        assert got == pytest.approx(want, rel=rel, abs=1e-300)
    else:
        assert got == want


def test_collapse_fits_reproduce_the_committed_record():
    record = json.loads((VALIDATION / "collapse_validation.json").read_text())
    fits = collapse_validation.fits(record["sweep"])
    # Refitted with this machine's BLAS: equal to the record to round-off.
    assert_same_numbers(fits, record["fits"], rel=1e-12)
    small = fits["small_a"]
    # The small-a slope through the origin, by hand from the committed rows.
    rows = [r for r in record["sweep"] if r["aspect"] in small["aspects"]]
    a = [r["aspect"] for r in rows]
    y = [r["normalised_runout"] for r in rows]
    by_hand = sum(ai * yi for ai, yi in zip(a, y, strict=True)) / sum(
        ai * ai for ai in a
    )
    assert small["slope_through_origin"] == pytest.approx(by_hand, rel=1e-12)
    assert small["gate"] == pytest.approx([0.9, 2.25])  # +-25 % of 1.2 .. 1.8


def test_speed_accuracy_page_and_fronts_reproduce_the_committed_record():
    record = json.loads((VALIDATION / "comparison" / "speed_accuracy.json").read_text())
    assert speed_accuracy.fronts(record) == record["fronts"]
    page = (ROOT / "docs" / "choosing.md").read_text()
    assert speed_accuracy.write_page(record, None) == page
    # The reference run-out of the record is the one the page quotes.
    ref = record["reference"]["collapse"]
    assert f"{ref:.4g}" in page
    assert 2.4 <= ref <= 3.6  # a = 2: 1.2 a .. 1.8 a


def test_committed_figures_are_stored_with_a_palette(tmp_path):
    """Figures of the studies: 256 colours, within 3 levels of the true colours."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from _reporting import save_png
    from PIL import Image

    fig, ax = plt.subplots(figsize=(4, 3))
    x = np.linspace(0, 1, 200)
    ax.imshow(np.outer(x, x), cmap="viridis")
    ax.plot(200 * x, 200 * x**2, "r-")
    true = io.BytesIO()
    fig.savefig(true, dpi=100, format="png")
    path = save_png(fig, tmp_path / "f.png", dpi=100)
    a = np.asarray(Image.open(true).convert("RGB"), float)
    b = np.asarray(Image.open(path).convert("RGB"), float)
    assert Image.open(path).mode == "P" and a.shape == b.shape
    assert np.abs(a - b).mean() < 3.0  # of 255 levels
    assert path.stat().st_size < 0.6 * len(true.getvalue())
    for png in (ROOT / "docs" / "validation").glob("*.png"):
        assert Image.open(png).mode == "P", png


def test_penetration_pages_quote_their_records():
    """The footing table quotes every run of its JSON; the cone table is made."""
    folder = ROOT / "docs" / "validation"
    page = (folder / "penetration_methods.md").read_text()
    runs = json.loads((folder / "penetration_methods.json").read_text())["runs"]
    assert len(runs) == 12
    for r in runs:
        assert f"| {r['bearing_factor']:.3f} |" in page, r["method"]
        assert f"| {r['final_bearing_factor']:.2f} |" in page, r["method"]
    cone = json.loads((folder / "cone_penetration.json").read_text())
    table = (folder / "cone_penetration.inc").read_text()
    for name, r in cone.items():
        assert f"| {name} |" in table and f"| {r['N_c']:.2f} |" in table
        # Teh & Houlsby's (1991) smooth-cone factor within 15 % in every case
        assert abs(r["N_c"] / (1.25 + 1.84 * math.log(r["rigidity_index"])) - 1) < 0.15


def test_examples_of_the_studies_helpers():
    """The docstring examples of the studies' shared helpers (Markdown tables,
    Pareto fronts, the runner's ``--set`` arguments): pytest's doctests cover
    the package only."""
    import doctest

    import _reporting
    import _study

    for module in (_reporting, _study):
        result = doctest.testmod(module)
        assert result.attempted > 0 and result.failed == 0


def test_cone_drops_helpers_count_holes_and_keep_the_face_on_the_cone():
    """Geometry: a lattice with one cell emptied has one hole; a face particle's
    velocity from the cone study's map moves normal to the face with the cone."""
    import cone_drops

    g = np.arange(4.0)
    x = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    cells = [
        (i + 4 * j, i + 1 + 4 * j, i + 5 + 4 * j, i + 4 + 4 * j)
        for j in range(3)
        for i in range(3)
    ]
    tris = np.array([t for a, b, c, d in cells for t in ((a, b, c), (a, c, d))])
    assert cone_drops.holes(x, tris) == 0
    assert cone_drops.holes(x, np.delete(tris, [8, 9], axis=0)) == 1  # the middle cell
    rng = np.random.default_rng(0)
    n = rng.normal(size=(5, 2))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    fixed = np.zeros((5, 2), bool)
    fixed[0, 0] = True  # on the axis
    face = np.array([True, True, False, True, False])
    T = cone_drops.velocity_map(fixed, face, n)
    V = (T @ np.eye(T.shape[1])[0]).reshape(5, 2)[face, 1]  # column 0: the cone
    assert np.allclose(V, 1.0)
    w = rng.normal(size=T.shape[1])
    u = (T @ w).reshape(5, 2)
    assert np.allclose(np.sum(u[face] * n[face], axis=1), w[0] * n[face, 1])
    assert u[0, 0] == 0.0
    assert T.shape[1] == 1 + 4 + 2  # V, the two free particles' dofs, two slides


def test_cone_sensitivity_nudge_keeps_the_run_s_own_constraints():
    """The nudge moves only free particles within reach of the tip, by about
    eps spacings, keeps the axis's particles on it and none inside the cone;
    the original simulation is left as it was."""
    import cone_sensitivity

    import skfem_npfem as npfem
    from skfem_npfem.scenes.footing.cone import build, sizes

    values = npfem.get_scene("cone-penetration").resolve(
        {"spacing": 0.0357 / 4, "shoulder_round": 2.0}
    )
    sim, g = build(values, progress=False).simulation, sizes(values)
    h, D, x0 = values["spacing"], values["diameter"], sim.particles.x.copy()
    eps, rng = 1e-2, np.random.default_rng(0)
    s = cone_sensitivity.nudged(sim, eps, h, 2 * D, g["z_tip"], rng)
    assert np.array_equal(sim.particles.x, x0)
    moved = np.linalg.norm(s.particles.x - x0, axis=1)
    far = np.hypot(x0[:, 0], x0[:, 1] - g["z_tip"]) > 2 * D
    held = np.asarray(sim.particles.fixed, bool).all(axis=1)
    assert np.all(moved[far | held] == 0.0)
    assert np.all(s.particles.x[x0[:, 0] == 0.0, 0] == 0.0)
    # Normal moves of eps h per coordinate: the mean size is sqrt(pi/2) eps h
    # (projected particles move less), within a factor of 1.5 over these.
    mean = moved[~far & ~held].mean() / (eps * h)
    assert math.sqrt(math.pi / 2) / 1.5 < mean < 1.5 * math.sqrt(math.pi / 2)
    dist, _, _ = sim.model.bodies[0].signed_distance(s.particles.x, s.time)
    assert dist.min() >= -1e-12 * D
