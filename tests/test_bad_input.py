"""Bad input through the public API and the CLI, property-based.

Every invalid input must raise a library error (:class:`ParameterError`, a
``ValueError``, or another documented subclass of :class:`NpfemError`) whose
message names the parameter, the offending value and what is allowed; the CLI
prints it as one line starting with ``error:`` on stderr, exits with 2 and shows
no traceback unless ``--debug`` is given.

"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from helpers import check_cli_error, run_cli
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from skfem import MeshTri

from skfem_npfem import (
    CheckpointError,
    DruckerPrager,
    FixedMesh,
    LinearElastic,
    Model,
    MohrCoulomb,
    NpfemError,
    ParameterError,
    Particles,
    Simulation,
    SolverOptions,
    Tresca,
    advance,
    get_scene,
)
from skfem_npfem.cli import main
from skfem_npfem.io import load_checkpoint, save_checkpoint

FAST = settings(max_examples=25, deadline=None)
FEW = settings(
    max_examples=10,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
TESTED_SCENES = ("elastic-column", "strip-footing")  # column-collapse: in progress


def check_parameter_error(err: BaseException, name: str, value=None) -> str:
    """The error is a ParameterError naming ``name`` (and ``value``) in one line."""
    assert isinstance(err, ParameterError), repr(err)
    assert isinstance(err, ValueError) and isinstance(err, NpfemError)
    msg = str(err)
    assert "\n" not in msg, msg
    assert err.name == name, msg
    assert msg.startswith(f"invalid {name}="), msg
    assert err.allowed.strip(), msg  # what is allowed
    if value is not None:
        assert repr(value) in msg or str(value) in msg, (value, msg)
    return msg


finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
non_finite = st.sampled_from([math.nan, math.inf, -math.inf])


# ---------------------------------------------------------- Particles.create ----
@FAST
@given(
    shape=st.one_of(
        st.tuples(st.integers(1, 6)),
        st.tuples(st.integers(1, 6), st.integers(4, 6)),
        st.tuples(st.integers(1, 6), st.just(1)),
        st.tuples(st.just(0), st.integers(2, 3)),
        st.tuples(st.integers(1, 3), st.integers(2, 3), st.integers(1, 2)),
    )
)
def test_positions_of_the_wrong_shape(shape):
    n = shape[0]
    with pytest.raises(ParameterError) as info:
        Particles.create(np.zeros(shape), np.ones(max(n, 1)))
    check_parameter_error(info.value, "x", tuple(shape))


@FAST
@given(
    n=st.integers(1, 8),
    d=st.sampled_from([2, 3]),
    bad=non_finite,
    data=st.data(),
)
def test_non_finite_positions(n, d, bad, data):
    x = np.zeros((n, d))
    i, k = data.draw(st.integers(0, n - 1)), data.draw(st.integers(0, d - 1))
    x[i, k] = bad
    with pytest.raises(ParameterError) as info:
        Particles.create(x, np.ones(n))
    msg = check_parameter_error(info.value, "x")
    assert f"at [{i}, {k}]" in msg and "non-finite" in msg


@FAST
@given(n=st.integers(1, 6), value=st.floats(max_value=0.0, allow_nan=False))
def test_zero_or_negative_mass(n, value):
    m = np.ones(n)
    m[-1] = value
    with pytest.raises(ParameterError) as info:
        Particles.create(np.zeros((n, 2)), m)
    check_parameter_error(info.value, "mass", float(value))


@FAST
@given(n=st.integers(1, 6), extra=st.integers(1, 3))
def test_mass_of_the_wrong_shape(n, extra):
    with pytest.raises(ParameterError) as info:
        Particles.create(np.zeros((n, 2)), np.ones(n + extra))
    check_parameter_error(info.value, "mass", (n + extra,))


@FAST
@given(
    field=st.sampled_from(["stress", "v", "fixed"]),
    rows=st.integers(1, 5),
    cols=st.integers(1, 7),
)
def test_state_arrays_of_the_wrong_shape(field, rows, cols):
    n = 3
    expected = {"stress": (n, 4), "v": (n, 2), "fixed": (n, 2)}[field]
    if (rows, cols) == expected:
        rows += 1
    kw = {field: np.zeros((rows, cols))}
    with pytest.raises(ParameterError) as info:
        Particles.create(np.zeros((n, 2)), np.ones(n), **kw)
    check_parameter_error(info.value, field, (rows, cols))


@FAST
@given(
    value=st.one_of(
        st.floats(max_value=-0.5, allow_nan=False, allow_infinity=False),
        st.floats(0.01, 0.99),
        non_finite,
    )
)
def test_material_ids_must_be_integers_ge_0(value):
    with pytest.raises(ParameterError) as info:
        Particles.create(np.zeros((2, 2)), np.ones(2), material=[0, value])
    check_parameter_error(info.value, "material")


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"x": [[0.0, 0.0], [1.0]], "mass": 1.0}, "x"),
        ({"x": "abc", "mass": 1.0}, "x"),
        ({"x": np.zeros((2, 2)), "mass": "heavy"}, "mass"),
        ({"x": np.zeros((2, 2)), "mass": 1.0, "stress": [[0.0] * 4, [0.0]]}, "stress"),
        ({"x": np.zeros((2, 2)), "mass": 1.0, "n_walls": -1}, "n_walls"),
    ],
)
def test_unreadable_arrays_name_the_argument(kwargs, name):
    # Before: raw numpy ValueErrors ("inhomogeneous shape", "could not
    # broadcast") that named no argument.
    with pytest.raises(ParameterError) as info:
        Particles.create(**kwargs)
    check_parameter_error(info.value, name)


# ----------------------------------------------------------------- materials ----
@FAST
@given(
    nu=st.one_of(
        st.floats(min_value=0.5, allow_nan=False),
        st.floats(max_value=-1.0, allow_nan=False),
        non_finite,
    )
)
def test_poisson_ratio_outside_open_interval(nu):
    for make in (
        lambda: LinearElastic(1e7, nu),
        lambda: MohrCoulomb(1e7, nu, c=1.0, phi=30.0),
        lambda: DruckerPrager(1e7, nu, c=1.0, phi=30.0),
    ):
        with pytest.raises(ParameterError) as info:
            make()
        msg = check_parameter_error(info.value, "nu")
        assert "(-1, 0.5)" in msg


@FAST
@given(E=st.one_of(st.floats(max_value=0.0, allow_nan=False), non_finite))
def test_young_modulus_must_be_positive(E):
    with pytest.raises(ParameterError) as info:
        LinearElastic(E, 0.3)
    check_parameter_error(info.value, "E")


@FAST
@given(rho=st.one_of(st.floats(max_value=-1e-300, allow_nan=False), non_finite))
def test_negative_density(rho):
    # rho = 0 is allowed for a material (weightless soil); the scenes that need
    # a weight require rho > 0 (see test_scene_parameters_out_of_range).
    with pytest.raises(ParameterError) as info:
        LinearElastic(1e7, 0.3, rho)
    check_parameter_error(info.value, "rho")


@FAST
@given(c=st.one_of(st.floats(max_value=-1e-300, allow_nan=False), non_finite))
def test_negative_cohesion(c):
    for make in (
        lambda: MohrCoulomb(1e7, 0.3, c=c, phi=30.0),
        lambda: Tresca(1e7, 0.3, c=c),
        lambda: DruckerPrager(1e7, 0.3, c=c, phi=30.0),
    ):
        with pytest.raises(ParameterError) as info:
            make()
        check_parameter_error(info.value, "c")


@FAST
@given(phi=st.one_of(st.floats(min_value=90.0, allow_nan=False), non_finite))
def test_friction_angle_of_90_degrees_or_more(phi):
    with pytest.raises(ParameterError) as info:
        MohrCoulomb(1e7, 0.3, c=1.0, phi=phi)
    msg = check_parameter_error(info.value, "phi")
    assert "[0, 90)" in msg


@FAST
@given(phi=st.floats(0.0, 89.0), excess=st.floats(1e-6, 60.0))
def test_dilation_above_friction(phi, excess):
    psi = phi + excess
    with pytest.raises(ParameterError) as info:
        MohrCoulomb(1e7, 0.3, c=1.0, phi=phi, psi=psi)
    msg = check_parameter_error(info.value, "psi", psi)
    assert f"{phi:g}" in msg  # the allowed range ends at phi


def test_boolean_is_not_a_number():
    with pytest.raises(ParameterError) as info:
        LinearElastic(True, 0.3)
    check_parameter_error(info.value, "E")


# ------------------------------------------------------------------- time step ----
def small_model():
    mesh = MeshTri().refined(1)
    p = Particles.create(mesh.p.T, np.ones(mesh.p.shape[1]))
    model = Model(dim=2, materials=[LinearElastic(1e7, 0.3, 1000.0)])
    return mesh, p, model


MESH, PART, MODEL = small_model()
bad_dt = st.one_of(st.floats(max_value=0.0, allow_nan=False), non_finite)


@FAST
@given(dt=bad_dt)
def test_advance_refuses_bad_time_step(dt):
    with pytest.raises(ParameterError) as info:
        advance(PART, MODEL, dt, FixedMesh(MESH.t))
    check_parameter_error(info.value, "dt")


@FAST
@given(dt=bad_dt)
def test_simulation_refuses_bad_time_step(dt):
    with pytest.raises(ParameterError) as info:
        Simulation(PART, MODEL, FixedMesh(MESH.t), dt)
    check_parameter_error(info.value, "dt")


@FAST
@given(dt=bad_dt)
def test_scene_refuses_bad_time_step(dt):
    with pytest.raises(ParameterError) as info:
        get_scene("elastic-column").resolve({"dt": dt})
    check_parameter_error(info.value, "dt")


@FAST
@given(scale=st.one_of(st.floats(max_value=0.0, allow_nan=False), non_finite))
def test_stress_scale_must_be_positive(scale):
    # Refused when the model is built, before any step.
    with pytest.raises(ParameterError) as info:
        Model(dim=2, materials=[LinearElastic(1e7, 0.3, 1000.0)], stress_scale=scale)
    check_parameter_error(info.value, "stress_scale")


def test_material_index_outside_the_list():
    # Before: the compliance of such nodes was uninitialised memory.
    p = PART.replace(material=np.full(PART.n, 3))
    with pytest.raises(ParameterError) as info:
        advance(p, MODEL, 1.0, FixedMesh(MESH.t))
    msg = check_parameter_error(info.value, "material", 3)
    assert "0..0" in msg


def test_particles_of_the_wrong_dimension():
    p3 = Particles.create(np.zeros((4, 3)), np.ones(4))
    with pytest.raises(ParameterError):
        advance(p3, MODEL, 1.0, FixedMesh(MESH.t))


def test_fixed_mesh_with_indices_out_of_range():
    with pytest.raises(ParameterError):
        advance(PART, MODEL, 1.0, FixedMesh(MESH.t + 100))


# -------------------------------------------------------------- scene values ----
param_names = st.text(
    alphabet=st.characters(codec="ascii", exclude_characters="=\n\r"),
    min_size=1,
    max_size=12,
)


@FAST
@given(scene=st.sampled_from(TESTED_SCENES), name=param_names)
def test_unknown_scene_parameter(scene, name):
    known = {p.name for p in get_scene(scene).params}
    if name in known:
        return
    with pytest.raises(ParameterError) as info:
        get_scene(scene).resolve({name: 1})
    msg = check_parameter_error(info.value, "parameter", name)
    assert "has parameters" in msg


def out_of_range(param) -> st.SearchStrategy:
    """Values a scene parameter must refuse."""
    if param.choices is not None:
        return st.text(max_size=8).filter(
            lambda t: t not in map(str, param.choices) and t.strip() != ""
        )
    if param.kind is bool:
        return st.sampled_from(["maybe", "2", "yes please", ""])
    bad = [st.sampled_from(["nan", "inf", "-inf", "abc", "", "1e400"])]
    if math.isfinite(param.lo):
        bad.append(
            st.floats(max_value=param.lo, allow_nan=False, allow_infinity=False)
            .filter(lambda v: v < param.lo or (param.lo_open and v == param.lo))
            .map(repr)
        )
    if math.isfinite(param.hi):
        bad.append(
            st.floats(min_value=param.hi, allow_nan=False, allow_infinity=False)
            .filter(lambda v: v > param.hi or (param.hi_open and v == param.hi))
            .map(repr)
        )
    if param.kind is int:
        bad.append(st.sampled_from(["1.5", "0.25"]))
    return st.one_of(*bad)


SCENE_PARAMS = [(scene, p) for scene in TESTED_SCENES for p in get_scene(scene).params]


@settings(max_examples=120, deadline=None)
@given(data=st.data())
def test_scene_parameters_out_of_range(data):
    scene, param = data.draw(st.sampled_from(SCENE_PARAMS))
    text = data.draw(out_of_range(param))
    with pytest.raises(ParameterError) as info:
        get_scene(scene).resolve({param.name: text})
    check_parameter_error(info.value, param.name, text)


# ------------------------------------------------------------------------ CLI ----
@FEW
@given(data=st.data())
def test_cli_out_of_range_values_exit_2_with_one_line(data):
    scene, param = data.draw(st.sampled_from(SCENE_PARAMS))
    text = data.draw(out_of_range(param))
    code, err = run_cli(["run", scene, "--set", f"{param.name}={text}", "--quiet"])
    check_cli_error(code, err, f"invalid {param.name}=")


@FEW
@given(
    item=st.text(
        alphabet=st.characters(codec="ascii", exclude_characters="="), max_size=10
    )
)
def test_cli_set_without_equals(item):
    if item.startswith("-"):
        item = "x" + item  # argparse would read it as an option
    code, err = run_cli(["run", "elastic-column", "--set", item, "--quiet"])
    check_cli_error(code, err, "invalid --set=", "name=value")


@FEW
@given(name=param_names)
def test_cli_unknown_parameter(name):
    # The CLI strips blanks around names (" c=1" sets c): only unknown names count.
    known = {p.name for p in get_scene("strip-footing").params}
    if name.strip() in known or name.startswith("-"):
        return
    code, err = run_cli(["run", "strip-footing", "--set", f"{name}=1", "--quiet"])
    check_cli_error(code, err, "invalid parameter=")


@pytest.mark.parametrize(
    ("sets", "name"),
    [
        (["nu=0.5"], "nu"),
        (["nu=-1"], "nu"),
        (["dt=0"], "dt"),
        (["dt=-1e-3"], "dt"),
        (["rho=0"], "rho"),
        (["E=-5"], "E"),
    ],
)
def test_cli_physical_limits_elastic_column(sets, name):
    argv = ["run", "elastic-column", "--quiet"]
    for s in sets:
        argv += ["--set", s]
    code, err = run_cli(argv)
    check_cli_error(code, err, f"invalid {name}=")


@pytest.mark.parametrize(
    ("sets", "name"),
    [
        (["c=-1"], "c"),
        (["phi=90"], "phi"),
        (["material=mohr-coulomb", "phi=20", "psi=30"], "psi"),
        (["material=tresca", "c=0"], "c"),
        (["material=mohr-coulomb", "c=0", "phi=0"], "c"),
        (["material=mohr-coulomb", "c=0", "phi=30", "rho=0"], "rho"),
        (["spacing=0.9"], "spacing"),
    ],
)
def test_cli_physical_limits_strip_footing(sets, name):
    argv = ["run", "strip-footing", "--quiet"]
    for s in sets:
        argv += ["--set", s]
    code, err = run_cli(argv)
    check_cli_error(code, err, f"invalid {name}=")


def test_cli_debug_shows_the_exception():
    with pytest.raises(ParameterError):
        main(["run", "elastic-column", "--set", "dt=-1", "--quiet", "--debug"])


@pytest.mark.parametrize("below", [True, False])
def test_cli_out_folder_under_a_regular_file(tmp_path, below):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    out = blocker / "sub" if below else blocker
    code, err = run_cli(["run", "elastic-column", "--out", str(out), "--quiet"])
    check_cli_error(code, err, "invalid out=", str(out))


def test_cli_summary_under_a_regular_file(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    code, err = run_cli(
        ["run", "elastic-column", "--summary", str(blocker / "s.json"), "--quiet"]
    )
    check_cli_error(code, err, "--summary")


def test_cli_out_folder_unwritable_is_one_line(tmp_path):
    # Whatever the wording, the CLI never shows a traceback (exit 2, one line).
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, err = run_cli(
        ["run", "elastic-column", "--out", str(blocker / "d"), "--quiet"]
    )
    check_cli_error(code, err, str(blocker))


# ---------------------------------------------------------------- checkpoints ----
def valid_checkpoint(folder: Path) -> Path:
    arrays = {
        "x": np.linspace(0.0, 1.0, 12).reshape(6, 2),
        "stress": np.arange(24.0).reshape(6, 4),
        "material": np.zeros(6, np.int64),
    }
    return save_checkpoint(
        folder / "checkpoint_000003.npz",
        arrays,
        {"step": 3, "time": 0.3, "dt": 0.1, "scene": "elastic-column"},
    )


@FAST
@given(blob=st.binary(max_size=2048))
def test_checkpoint_of_random_bytes(blob):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "checkpoint_000001.npz"
        path.write_bytes(blob)
        with pytest.raises(CheckpointError) as info:
            load_checkpoint(path)
    msg = str(info.value)
    assert str(path) in msg and "\n" not in msg


@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_truncated_or_bit_flipped_checkpoint(data):
    with tempfile.TemporaryDirectory() as d:
        path = valid_checkpoint(Path(d))
        good = path.read_bytes()
        ref_arrays, ref_meta = load_checkpoint(path)
        if data.draw(st.booleans(), label="truncate"):
            cut = data.draw(st.integers(0, len(good) - 1), label="cut")
            blob = good[:cut]
        else:
            pos = data.draw(st.integers(0, len(good) - 1), label="pos")
            flip = data.draw(st.integers(1, 255), label="xor")
            blob = bytearray(good)
            blob[pos] ^= flip
            blob = bytes(blob)
        path.write_bytes(blob)
        try:
            arrays, meta = load_checkpoint(path)
        except CheckpointError as err:
            assert str(path) in str(err) and "\n" not in str(err)
            return
    # A flip in bytes the format does not read (zip timestamps, padding) may
    # load; then the content must be exactly the original.
    assert meta == ref_meta
    assert arrays.keys() == ref_arrays.keys()
    for k, a in ref_arrays.items():
        np.testing.assert_array_equal(arrays[k], a)


# zipfile raises NotImplementedError / RuntimeError for these header fields;
# load_checkpoint must still answer with a CheckpointError.
@pytest.mark.parametrize(
    ("offset", "xor"),
    [(6, 0xFF), (8, 0x01), (10, 99)],
    ids=["version", "encrypted-flag", "compression-method"],
)
def test_checkpoint_with_corrupted_zip_header(tmp_path, offset, xor):
    path = valid_checkpoint(tmp_path)
    blob = bytearray(path.read_bytes())
    central = bytes(blob).find(b"PK\x01\x02")  # first central-directory entry
    blob[central + offset] ^= xor
    path.write_bytes(bytes(blob))
    with pytest.raises(CheckpointError):
        load_checkpoint(path)


def test_cli_resume_from_corrupted_checkpoint(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "checkpoint_000001.npz").write_bytes(b"\x00garbage" * 50)
    code, err = run_cli(
        ["run", "elastic-column", "--out", str(out), "--resume", "--quiet"]
    )
    check_cli_error(code, err, "checkpoint", "checkpoint_000001.npz")


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"reproducible": "yes"}, "reproducible"),
        ({"reproducible": 1}, "reproducible"),
        ({"max_threads": -1}, "max_threads"),
        ({"max_threads": 1.5}, "max_threads"),
    ],
)
def test_solver_options_name_the_bad_setting(kwargs, name):
    with pytest.raises(ParameterError) as info:
        SolverOptions(**kwargs)
    assert info.value.name == name


def test_cli_rejects_a_non_boolean_reproducible():
    code, err = run_cli(
        ["run", "elastic-column", "--set", "reproducible=maybe", "--quiet"]
    )
    check_cli_error(code, err, "reproducible", "maybe")
