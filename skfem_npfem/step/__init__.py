"""One N-PFEM step: the cone program built from the particles, solved, read back.

The data flow of :func:`advance` (in :mod:`.stages`) goes through these modules:

* :mod:`.model` -- what is solved: materials, mode, walls, time scheme, options;
* :mod:`.program` -- the cone program's input (:class:`ConeInput`) and its
  blocks;
* :mod:`.families`, :mod:`.stabilisation`, :mod:`.volume` -- the program's terms:
  the yield cones per material family, the consistent element-residual
  stabilisation and the volume correction;
* :mod:`.conic` -- scaling, Clarabel's problem and the solution read back from the
  duals (:class:`ConeSolution`);
* :mod:`.solver`, :mod:`.backends` -- solver options and the direct linear solvers;
* :mod:`.kinematics` -- stress rotation, strain measures, energies;
* :mod:`.operators` -- stage 1: the mesh, its strain operator, the contacts
  and the cone program's input (:class:`~.operators.StepOperators`);
* :mod:`.update` -- stage 3: new particles from the solution, moved and put
  back from the boundaries;
* :mod:`.boundary_jobs` -- the step asking the model's boundaries (walls,
  rigid bodies) each job once;
* :mod:`.records` -- what a step leaves: :class:`Step`, :class:`StepRecord`
  and the :class:`StepState` the next step starts from;
* :mod:`.stages` -- :func:`advance`: the three stages of a step in a line.
"""

from .conic import ConeSolution, solve_step
from .model import Model
from .program import ConeInput
from .records import Step, StepRecord
from .solver import SolverOptions
from .stages import advance

__all__ = [
    "ConeInput",
    "ConeSolution",
    "Model",
    "SolverOptions",
    "Step",
    "StepRecord",
    "advance",
    "solve_step",
]
