"""The documentation site builds without a warning, and its tutorials run.

One Sphinx build (``python -m sphinx -W -b html docs OUT``, the command of
``docs/conf.py``) executes the six tutorials (MyST notebooks; an error in a cell
fails the build).  The numbers the tutorials print are then read back from the
built pages and checked against their closed-form references, the API inventory
is checked against ``skfem_npfem.__all__``, and the gallery against ``demos/``.
Needs the ``docs`` extra (installed by the README's test command); skipped
without it.  Marked ``docs``, which a plain ``pytest`` leaves out: run with
``pytest -m docs``.
"""

import html
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

import skfem_npfem

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.docs

for module in (
    "sphinx",
    "myst_nb",
    "furo",
    "ipykernel",
    "sphinx-mathjax-offline",
    "sphinx_gallery",
):
    pytest.importorskip(module, reason="needs the docs extra: pip install '.[docs]'")


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("docs")
    html_dir = out / "html"
    cmd = [
        sys.executable,
        "-m",
        "sphinx",
        "-W",
        "--keep-going",
        "-q",
        "-b",
        "html",
        "-d",
        str(out / "doctrees"),
        str(ROOT / "docs"),
        str(html_dir),
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    warnings = [ln for ln in proc.stderr.splitlines() if "WARNING" in ln]
    warnings = [ln for ln in warnings if "IPKernelApp" not in ln]  # kernel chatter
    assert proc.returncode == 0 and not warnings, proc.stderr[-5000:]
    return html_dir


def page_text(site: Path, name: str) -> str:
    """The visible text of a built page (tags removed)."""
    raw = (site / name).read_text(encoding="utf-8")
    raw = re.sub(r"<(script|style)\b.*?</\1>", "", raw, flags=re.S)
    return html.unescape(re.sub(r"<[^>]+>", "", raw))


#: Attributes through which a page loads something (a hyperlink in the text,
#: ``<a href>``, loads nothing and may point anywhere).
LOADING = re.compile(
    r"<(script|link|img|iframe|source|video|audio|embed|object)\b[^>]*?"
    r"\b(src|href|data|srcset)\s*=\s*[\"']([^\"']*)[\"']",
    re.I | re.S,
)


def test_pages_load_nothing_from_another_host(site):
    # Offline, a page must render whole: scripts (MathJax), styles, fonts and
    # images come from the site itself, never from a CDN.
    foreign = []
    pages = [p for p in site.rglob("*.html") if "_static" not in p.parts]
    assert len(pages) > 20
    for page in pages:
        raw = page.read_text(encoding="utf-8")
        for tag, attr, url in LOADING.findall(raw):
            if re.match(r"(https?:)?//", url.strip(), re.I):
                foreign.append(f"{page.relative_to(site)}: <{tag} {attr}={url}>")
    assert not foreign, "\n".join(foreign[:20])


def test_formulas_render_with_the_sites_own_mathjax(site):
    raw = (site / "theory.html").read_text(encoding="utf-8")
    src = re.search(r"<script[^>]*src=\"([^\"]*tex-chtml\.js)\"", raw)
    assert src, "theory.html loads no MathJax"
    assert (site / src.group(1)).is_file()
    assert (site / "_static/mathjax/output/chtml/fonts/woff-v2").is_dir()


def test_every_public_name_is_in_the_api_reference(site):
    from sphinx.util.inventory import InventoryFile

    with open(site / "objects.inv", "rb") as f:
        inv = InventoryFile.load(f, "", lambda base, uri: uri)
    documented = {name for domain in inv.values() for name in domain}
    public = {f"skfem_npfem.{n}" for n in skfem_npfem.__all__ if n != "__version__"}
    assert public <= documented, sorted(public - documented)


def test_gallery_has_a_page_per_demo(site):
    # The examples are sphinx-gallery's pages (gallery/STEM.html, with the
    # script to download); the studies are listed by docs/_ext/npfem_studies.py.
    for script in sorted((ROOT / "demos").glob("*.py")):
        page = site / "gallery" / f"{script.stem}.html"
        assert page.exists(), page
        assert script.name in page_text(site, page.relative_to(site))
    # (a study's shared helper module, ``_common.py``, is no study of its own)
    for script in sorted((ROOT / "demos" / "studies").glob("[!_]*.py")):
        page = site / "gallery" / f"studies-{script.stem}.html"
        assert page.exists(), page
        text = page_text(site, page.relative_to(site))
        assert f"demos/studies/{script.name}" in text


def test_gallery_examples_ran_and_show_their_figures(site):
    # The short examples run at build time: the one-step page shows the
    # printed error of the elastic column against sigma_yy = -rho g (H - y) and
    # the figure the script saved (sigma_yy.png, shown as the block's image).
    text = page_text(site, "gallery/one_step_by_hand.html")
    err = float(re.search(r"sigma_yy relative L2 error: ([\d.e+-]+)", text)[1])
    assert err < 5e-3
    raw = (site / "gallery" / "one_step_by_hand.html").read_text()
    assert re.search(r'<img [^>]*src="[^"]*sphx_glr_one_step_by_hand_001\.png"', raw)


def test_tutorial_one_step_recovers_the_displacement_from_the_duals(site):
    text = page_text(site, "tutorials/one_step.html")
    # Tresca block in uniform compression: sigma_yy = (lambda + G) eps - c.
    got, exact = map(
        float,
        re.search(r"sigma_yy = (-?[\d.]+) Pa, exact (-?[\d.]+) Pa", text).groups(),
    )
    assert abs(got / exact - 1) < 1e-6
    # The elastic step: 0 IPM iterations, du of the duals = du of K u = f.
    iters, diff = re.search(
        r"(\d+) iterations; \|du\(duals\) - du\(K solve\)\| = ([\d.e+-]+) delta", text
    ).groups()
    assert int(iters) == 0 and float(diff) < 1e-8
    assert "cones: {'ZeroConeT(30)': 1, 'SecondOrderConeT(3)': 25}" in text


def test_tutorial_prandtl_matches_two_plus_pi(site):
    text = page_text(site, "tutorials/prandtl.html")
    q = float(re.search(r"q/c = ([\d.]+)\s+\(2 \+ pi", text).group(1))
    assert abs(q / (2 + math.pi) - 1) < 0.01
    refined = float(re.search(r"Tresca, smooth, b/h = 16\s+N =\s+([\d.]+)", text)[1])
    assert abs(refined / (2 + math.pi) - 1) < 0.002


def test_tutorial_collapse_main_body_is_in_the_experimental_band(site):
    # The main body's run-out, not the 99 % front (which stray grains of a
    # coarse run carry ahead), is checked against the experiments.
    text = page_text(site, "tutorials/column_collapse.html")
    a2 = float(re.search(r"a = 2\.0: 99 % front .*? main body ([\d.]+)", text)[1])
    a1 = float(re.search(r"a = 1: main body \(L_inf - L0\)/L0 = ([\d.]+)", text)[1])
    # a = 2: between Lube et al.'s two branches 1.2 a and 1.9 a^(2/3) (their
    # transition band); a = 1: Lube's 1.2 a to Lajeunesse et al.'s 1.8 a.
    assert 2.4 <= a2 <= 1.9 * 2 ** (2 / 3) and 1.2 <= a1 <= 1.8
    assert "detached from the main body" in text  # the a = 2 run's warning
    assert text.count("plastic_strain_eq") >= 1


def test_tutorial_own_scene_slides_like_a_rigid_block(site):
    text = page_text(site, "tutorials/own_scene.html")
    slide, exact = map(
        float,
        re.search(
            r"slid ([\d.]+) m in [\d.]+ s; rigid-body answer ([\d.]+) m", text
        ).groups(),
    )
    assert abs(slide / exact - 1) < 1e-3
    # The level layer with its geostatic stress rests on the floor: the floor
    # forces (wall_force) carry its weight.
    force, weight = map(
        float,
        re.search(r"floor force ([\d.]+) N/m .*?weight ([\d.]+) N/m", text).groups(),
    )
    assert abs(force / weight - 1) < 1e-5
    code = re.search(
        r"import numpy as np.*?records = sim\.run\(t_end=0\.3\)", text, re.S
    )
    assert code and code.group(0).count("\n") < 60


def test_tutorial_choosing_reads_the_committed_study(site):
    text = page_text(site, "tutorials/choosing.html")
    n = int(re.search(r"checked the errors of (\d+) runs against 2 \+ pi", text)[1])
    assert n > 0


def test_tutorial_own_body_matches_uniaxial_strain(site):
    text = page_text(site, "tutorials/own_body.html")
    m = re.search(r"force ([\d.]+) N/m, uniaxial strain ([\d.]+) N/m", text)
    assert float(m[1]) == pytest.approx(float(m[2]), rel=1e-6)
    deepest = re.search(r"deepest particle inside the pipe: ([\d.e+-]+) m", text)
    assert float(deepest[1]) <= 0.5 * 0.05
    # In 3D: the plate on a quarter block, and the sphere pressed into it
    m = re.search(r"force ([\d.]+) N, uniaxial strain ([\d.]+) N\b", text)
    assert float(m[1]) == pytest.approx(float(m[2]), rel=1e-6)
    inside = re.findall(r"deepest particle inside ([\d.e+-]+) m", text)
    assert len(inside) == 3 and max(map(float, inside)) <= 0.5 * 0.125
