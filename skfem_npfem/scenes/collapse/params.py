"""The plane-strain column collapse's parameters, metrics and default settings.

The defaults the scene runs at (the stabilisation factor, the volume correction
and when it applies, the limits of the material scales it accepts) are named
constants here, so that studies and tests can refer to them.
"""

from __future__ import annotations

from ...constants import GRAVITY
from ..common import (
    elastic_params,
    fidelity_params,
    solver_params,
)
from ..limits import SPACING
from ..methods import METHOD_METRICS, METHOD_PARAMS
from ..params import ANGLE, POSITIVE, Param
from ..refinement import INSERT_METRICS, insert_params
from ..shaking import kh_param
from ..water import WATER_PARAMS
from .runout import (
    DETACHED_WARNING,
)

__all__ = [
    "COLLAPSE_STABILISATION",
    "COLLAPSE_VOLUME_CORRECTION",
    "MATERIALS",
    "MAX_STIFFNESS_RATIO",
    "MAX_STRENGTH_RATIO",
    "METRICS",
    "PARAMS",
    "VOLUME_CORRECTION_STRAIN",
]


MATERIALS = ("mohr-coulomb", "drucker-prager")


#: Largest cohesion in units of rho g H0 (beyond it, displacements of a
#: standing column grow with c: measured 3x at 1.4e4, 36x at 1.4e5).
MAX_STRENGTH_RATIO = 1e4


#: Largest Young's modulus in units of rho g H0 (measured over 0.3 s: 1.4e9
#: and 1.9e9 run, 9.9e9 fails at step 38, 2.5e12 at step 5).
MAX_STIFFNESS_RATIO = 2e9


#: Default stabilisation factor beta of N-PFEM in this scene (docs/validation.md:
#: the measured roughness and run-out against it).
COLLAPSE_STABILISATION = 30.0


#: Default volume-correction rate kappa of N-PFEM in plane strain
#: (docs/validation.md, "At the default spacing"), for a material whose own
#: volume barely changes: psi = 0 and an elastic strain scale rho g H0 / E of
#: at most VOLUME_CORRECTION_STRAIN.  The correction returns every change of
#: the mesh volume against sum m / rho, so dilatancy (psi > 0) and the elastic
#: volume change of a soft column (the E = 1 kPa pancake of the extremes
#: matrix swells by 40 % as its initial stresses relax) would be undone; for
#: those the default is 0.
COLLAPSE_VOLUME_CORRECTION = 0.05


VOLUME_CORRECTION_STRAIN = 1e-2


PARAMS = [
    Param("aspect", 2.0, "-", "aspect ratio a = H0/L0", float, **POSITIVE),
    Param(
        "half_width",
        0.2,
        "m",
        "column half-width L0 (the width of the half column)",
        float,
        **POSITIVE,
    ),
    Param(
        "symmetric",
        True,
        "-",
        "true: half column against a smooth wall at x = 0; false: free-standing "
        "column of width 2 L0 centred at x = 0",
        bool,
    ),
    Param(
        "spacing",
        None,
        "m",
        "particle (lattice) spacing (default L0/22: 1 035 particles at a = 2)",
        float,
        **SPACING,
    ),
    Param("material", "mohr-coulomb", "-", "yield criterion", str, MATERIALS),
    Param("rho", 1800.0, "kg/m^3", "density", float, **POSITIVE),
    *elastic_params(1.0e7),
    Param(
        "phi",
        30.0,
        "deg",
        "friction angle",
        float,
        lo=0,
        hi=90,
        lo_open=True,
        hi_open=True,
    ),
    Param("psi", 0.0, "deg", "dilation angle (<= phi)", float, lo=0, hi=90),
    Param("c", 0.0, "Pa", "cohesion", float, lo=0),
    Param(
        "floor_friction",
        None,
        "deg",
        "floor friction angle (default: phi)",
        float,
        **ANGLE,
    ),
    kh_param(
        "along +x, away from the wall x = 0 (negative: toward it)",
        "a number for the whole run, or a file of rows t, k_h, a recorded "
        "history from the release (plane strain and box only: it would break "
        "an axis's or a symmetry plane's symmetry)",
    ),
    Param(
        "K0",
        None,
        "-",
        "initial s_xx / s_yy (at-rest coefficient; default Jaky's 1 - sin phi: "
        "0.5 at the default phi = 30). A cohesionless Mohr-Coulomb K0 outside "
        "the yield cone is refused",
        float,
        **POSITIVE,
    ),
    Param("gravity", GRAVITY, "m/s^2", "gravitational acceleration", float, **POSITIVE),
    Param("dt", 5e-3, "s", "time step (halved on solver failure)", float, **POSITIVE),
    Param(
        "max_displacement",
        None,
        "-",
        "adaptive dt: keep the largest particle displacement per step below this "
        "fraction of the spacing (default: off, fixed dt)",
        float,
        **POSITIVE,
    ),
    Param("t_end", 1.0, "s", "end time", float, **POSITIVE),
    Param(
        "rest_fraction",
        1e-3,
        "-",
        "stop when the kinetic energy < rest_fraction * its maximum (0: never)",
        float,
        lo=0,
        hi=1,
        hi_open=True,
    ),
    Param(
        "min_time",
        None,
        "s",
        "earliest stop at rest (default 2 sqrt(H0/g))",
        float,
        lo=0,
    ),
    Param(
        "alpha",
        1.3,
        "-",
        "alpha-shape factor (circumradius < alpha h)",
        float,
        lo=1.0,
        hi=3.0,
    ),
    Param(
        "theta1",
        1.0,
        "-",
        "time-integration parameter theta1",
        float,
        lo=0.5,
        hi=1.0,
    ),
    Param(
        "theta2",
        1.0,
        "-",
        "time-integration parameter theta2 (impact restitution 1/theta2 - 1: "
        "1/2 makes impacts elastic, keep 1)",
        float,
        lo=0.5,
        hi=1.0,
    ),
    Param("output_every", 5, "-", "write a VTU every k steps", int, lo=1),
    Param(
        "checkpoint_every",
        20,
        "-",
        "checkpoint every k steps (with --out)",
        int,
        lo=1,
    ),
    *insert_params(
        "surface",
        "a graded lattice: the spacing in a band of refine_band spacings along "
        "the free surfaces and the floor, twice it in the column's core; ",
        ratio=0.0,
        strain=True,
    ),
    Param(
        "refine_band",
        4.0,
        "-",
        "refine=surface: width of the fine band along the free surfaces and the "
        "floor, in spacings",
        float,
        lo=1.0,
        hi=100.0,
    ),
    *WATER_PARAMS,
    *METHOD_PARAMS,
    *fidelity_params(
        COLLAPSE_STABILISATION,
        " in plane strain, 0 for box",
        COLLAPSE_VOLUME_CORRECTION,
        f" in plane strain with psi = 0 and rho g H0 / E <= "
        f"{VOLUME_CORRECTION_STRAIN:g}",
        "full",
        " in every geometry",
    ),
    *solver_params(),
]


METRICS = {
    "runout": "final run-out L_inf: the 99 % mass front, m (from x = 0 when "
    "symmetric, else half the width between the 0.5 % and 99.5 % mass quantiles)",
    "normalised_runout": "(L_inf - L0) / L0",
    "runout_main_body": "edge of the meshed main body (largest cluster with gaps "
    "below 3 spacings), m",
    "normalised_runout_main_body": "(runout_main_body - L0) / L0: the run-out of "
    "the main body, free of detached grains",
    "detached_mass_fraction": "mass outside the main body (inactive grains and "
    "small clusters) / total mass at the end; above "
    f"{DETACHED_WARNING:.0%} a warning says the 99 % front may be set by them",
    "runout_tip": "the farthest grain, m",
    "reference_runout_lube": "Lube et al. 2005: 1.2 a (a <= 1.8), 1.9 a^(2/3) "
    "(a >= 2.8), log-linear in between",
    "final_height": "H_inf / L0 (highest particle of the main body)",
    "height_ratio": "H_inf / H0",
    "collapse_time": "time the front stops (stays within one spacing of its final "
    "position), s; null when the run ended before rest (t_end)",
    "collapse_time_normalised": "collapse_time / sqrt(H0 / g)",
    "at_rest": "the run ended by the at-rest rule (not t_end); false: the run-out "
    "and height are not final (see warnings)",
    "warnings": "list of one-line warnings (the run reached t_end before the "
    f"at-rest rule stopped it; detached mass above {DETACHED_WARNING:.0%}); the "
    "CLI prints each on stderr",
    "volume_change": "relative mesh-volume (area) change, end vs t = 0",
    "mass_change": "relative change of the total particle mass (0: exact)",
    "max_kinetic_energy": "largest kinetic energy, J (per metre of depth)",
    "final_kinetic_energy": "kinetic energy at the end, J",
    "n_inactive_final": "particles outside every element at the end (ballistic)",
    "n_particles": "number of particles (at the end)",
    "inserted": INSERT_METRICS["inserted"],
    "merged": INSERT_METRICS["merged"],
    **METHOD_METRICS,
}
