"""The time loop: many steps with output, checkpoints and adaptive time stepping.

:class:`Simulation` drives :func:`~skfem_npfem.advance`: fixed or adaptive
time step (halve and retry when the solver fails, grow back after successes),
an end time or a stopping rule (:class:`AtRest`), callbacks, progress
reporting, VTU output as steps finish, and checkpoints to resume from (the
files themselves are :mod:`skfem_npfem.io`'s).  Each step's arrays reach the
callbacks and the writer in a :class:`~skfem_npfem.step.stages.Step` and are
dropped after them; the run keeps one scalar
:class:`~skfem_npfem.step.stages.StepRecord` per step.
"""

from __future__ import annotations

import math
import signal
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from skfem import Mesh

from ..boundary import start_clear
from ..errors import ParameterError, RunInterrupted, SolverError
from ..io import read_checkpoint, water_point_data, write_checkpoint
from ..mesh.sources import MeshSource, as_mesh_source, mesh_particles
from ..particles import Particles
from ..profiles import profile_point_data
from ..step.kinematics import energies
from ..step.model import Model
from ..step.stages import Step, StepRecord, StepState, advance
from .control import INTERVAL, AbandonStep, Progress, SignalGuard, next_dt
from .penetration import PenetrationCheck
from .refining import Refiner, refined_point_data
from .rest import AtRest
from .statistics import peak_memory_mb, run_statistics

__all__ = ["AtRest", "Simulation", "peak_memory_mb"]


class Simulation:
    """Run many steps with output, checkpoints and adaptive time stepping.

    Parameters
    ----------
    particles : Particles
        Initial state.
    model : Model
        Physics and solver settings.
    mesh_source : callable, skfem.Mesh or ndarray (d+1, ne)
        See :func:`advance` (a mesh or a connectivity is one
        :class:`~skfem_npfem.FixedMesh` for the whole run).
    dt : float
        Initial (and maximum) time step, s.
    adaptive : bool
        On a solver failure halve ``dt`` and retry (down to ``dt_min``); grow it back
        by 2x after ``grow_after`` consecutive successes.
    dt_min : float or None
        Smallest step allowed (default ``dt / 64``).
    max_displacement : float or None
        Displacement-based step control: keep the largest particle displacement
        per step below ``max_displacement * h`` (h: the mean particle spacing of
        the step's mesh).  The step that exceeds it is kept and the next step is
        shortened to ``0.9 * dt * limit / max|du|`` (never below ``dt_min``); the
        step grows back (at most 2x per step, never above the initial ``dt``)
        while the displacement stays below the limit.  None: off.
    writer : ResultWriter or None
        Receives a VTU per output step.
    output_every : int
        Write every k-th step (the last step is always written).
    checkpoint_dir : path or None
        Folder for ``checkpoint_XXXXXX.npz`` files.
    checkpoint_every : int
        Steps between checkpoints.
    callbacks : list of callables
        ``f(sim, particles, result)`` after every step, with the new particles
        and the :class:`~skfem_npfem.step.stages.Step` (``result.record`` is
        the kept :class:`~skfem_npfem.step.stages.StepRecord`: store scene values in
        ``result.record.extra``); return True to stop.
    progress : bool or None
        Progress on stderr (None: on): on a terminal one line rewritten after
        every step, otherwise a line every ``progress_interval`` seconds (and
        the first and last steps); see :mod:`skfem_npfem.run.control`.
    meta : dict
        Stored in checkpoints (scene name, parameters).
    extra_point_data : callable or None
        ``f(particles) -> dict`` of more point data for the VTU files.
    stepper : callable or None
        The step, ``stepper(particles, model, dt, mesh_source, step=k,
        start=state) -> (particles, Step)``, where ``state`` is the
        :class:`~skfem_npfem.step.records.StepState` at the start of the step
        and the returned step's ``state`` the one at its end; None: N-PFEM's
        :func:`~skfem_npfem.step.stages.advance`.  Another method (FEM with remapping,
        explicit SPFEM: :mod:`skfem_npfem.baseline`) plugs in here and may keep
        more state in a subclass of :class:`Particles`; checkpoints keep it.
    refiner : Refiner or None
        Adds (and merges) particles before each step, where the soil
        stretches (:class:`~skfem_npfem.run.refining.Refiner`); None: off.

    Raises
    ------
    ParameterError
        If ``dt`` is not a finite time > 0, or ``max_displacement`` is given
        and not > 0.  :meth:`run` raises
        :class:`~skfem_npfem.errors.SolverError` when a step fails at the
        smallest allowed ``dt`` (naming the step and what to change) and
        :class:`~skfem_npfem.errors.RunInterrupted` on SIGINT/SIGTERM.
    """

    def __init__(
        self,
        particles: Particles,
        model: Model,
        mesh_source: MeshSource | Mesh | np.ndarray,
        dt: float,
        *,
        adaptive: bool = False,
        dt_min: float | None = None,
        grow_after: int = 4,
        max_displacement: float | None = None,
        writer: Any = None,
        output_every: int = 1,
        checkpoint_dir: str | Path | None = None,
        checkpoint_every: int = 0,
        callbacks: list[Callable[..., Any]] | None = None,
        progress: bool | None = None,
        meta: dict | None = None,
        extra_point_data: Callable[[Particles], dict[str, np.ndarray]] | None = None,
        stepper: Callable[..., tuple[Particles, Step]] | None = None,
        refiner: Refiner | None = None,
    ) -> None:
        if not (isinstance(dt, int | float) and math.isfinite(dt) and dt > 0):
            raise ParameterError("dt", dt, "a finite time step > 0 (s)")
        self.particles = particles
        self.model = model
        self.mesh_source = as_mesh_source(mesh_source)
        self.dt_max = float(dt)
        self.dt = float(dt)
        self.adaptive = adaptive
        self.dt_min = float(dt_min) if dt_min is not None else dt / 64.0
        self.grow_after = grow_after
        if max_displacement is not None and not (
            isinstance(max_displacement, int | float)
            and math.isfinite(max_displacement)
            and max_displacement > 0
        ):
            raise ParameterError(
                "max_displacement", max_displacement, "a number > 0 (fraction of h)"
            )
        self.max_displacement = max_displacement
        self.writer = writer
        self.output_every = max(1, int(output_every))
        self.checkpoint_dir = Path(checkpoint_dir) if checkpoint_dir else None
        self.checkpoint_every = int(checkpoint_every)
        self.callbacks = list(callbacks or [])
        self.progress = True if progress is None else bool(progress)
        #: Seconds between progress lines when stderr is not a terminal.
        self.progress_interval = INTERVAL
        self._last_checkpoint: dict[int, Path] = {}
        #: Peak memory of the processes that ran the steps before a restored
        #: checkpoint, MiB (0 for a run started here).
        self._peak_memory_before = 0.0
        self.meta = dict(meta or {})
        self.extra_point_data = extra_point_data
        self.stepper, self.refiner = stepper, refiner
        self.penetration_check = PenetrationCheck()  # a body's half a spacing
        #: What the next step starts from besides the particles (time, filter).
        self.state = StepState()
        self.after_output = lambda sim: None  # after a step's files are written
        self.step = 0
        self.records: list[StepRecord] = []
        self._successes = 0
        self.last_record: StepRecord | None = None
        #: Why the last run ended before its step count or end time: the stop
        #: rule's ``label`` (:class:`AtRest`: ``"at rest"``), ``"stop rule
        #: met"``, ``"callback"``; None otherwise.
        self.stopped_by: str | None = None
        #: Mass and energies of the initial state (see :func:`energies`).
        self.initial = energies(particles, model.gravity)
        if model.bodies:
            if stepper is not None:
                raise ParameterError(
                    "stepper",
                    getattr(stepper, "__name__", type(stepper).__name__),
                    "None with rigid bodies (they are part of the N-PFEM step)",
                )
            self.particles = particles = start_clear(model.bodies, particles)

    @property
    def time(self) -> float:
        """Time at the end of the last step, s (``state.time``)."""
        return self.state.time

    # -- output ---------------------------------------------------------------
    def point_data(self, p: Particles, active: np.ndarray | None) -> dict:
        """Point data written to the VTU files."""
        act = np.zeros(p.n, bool)
        if active is not None:
            act[active] = True
        data = {"displacement": p.u, "velocity": p.v, "stress": p.stress}
        data |= {"plastic_strain_eq": p.eps_p, "mass": p.mass, "active": act}
        # Mesh sources that know the free surface (AlphaShapeMesher) report it
        # for the mesh the step was solved on.
        free = getattr(self.mesh_source, "free_surface", None)
        flags = free() if callable(free) else None
        if flags is not None:
            data["free_surface"] = flags
        data |= profile_point_data(p) | refined_point_data(p)  # if any
        if (law := self.model.strength_law) is not None:  # softening x rate
            f = law.factors(p.eps_p, p.shear_rate, p.x, p.mass)
            data["strength_law_factor"] = f
        if self.extra_point_data is not None:
            data.update(self.extra_point_data(p))
        return data

    def write_output(self, cells_global: np.ndarray | None, active) -> None:
        """Write the current particles as one VTU step."""
        if self.writer is None:
            return
        # An axisymmetric result says so in its field data: points are (r, z)
        # and the third stress component is the hoop stress.
        axisymmetric = getattr(self.model, "axisymmetric", False)
        self.writer.write(
            self.step,
            self.time,
            self.particles.x,
            cells_global,
            self.point_data(self.particles, active)
            | water_point_data(self.particles, self.model, active, cells_global),
            field_data={"Axisymmetric": 1.0} if axisymmetric else None,
        )

    def save_checkpoint(self) -> Path | None:
        """Write ``checkpoint_<step>.npz`` (see :mod:`skfem_npfem.io`)."""
        if self.checkpoint_dir is None:
            return None
        state = {
            **self.meta,
            "step": self.step,
            "time": self.time,
            "dt": self.dt,
            "successes": self._successes,
            "initial": self.initial,
            "records": [r.as_dict() for r in self.records],
            "peak_memory_mb": max(self._peak_memory_before, peak_memory_mb()),
        }
        path = write_checkpoint(self.checkpoint_dir, self.step, self.particles, state)
        self._last_checkpoint = {self.step: path}
        return path

    def restore(self, path: str | Path) -> dict:
        """Continue from a checkpoint written by :meth:`save_checkpoint`.

        Restores the particles, step, time, the adaptive time-step state and the
        step records, so that the continued run repeats the uninterrupted one
        step for step.  The particles are read back as the class of the current
        ones (a method's state subclass keeps its extra arrays).  Returns the
        checkpoint's metadata.
        """
        self.particles, meta = read_checkpoint(path, type(self.particles))
        self.step = int(meta["step"])
        self.dt = float(meta["dt"])
        self._successes = int(meta.get("successes", 0))
        self.initial = dict(meta.get("initial", self.initial))
        self.records = [StepRecord.from_dict(r) for r in meta.get("records", [])]
        self.last_record = self.records[-1] if self.records else None
        self.state = StepState.resumed(float(meta["time"]), self.last_record)
        self._peak_memory_before = float(meta.get("peak_memory_mb", 0.0))
        return meta

    # -- loop -----------------------------------------------------------------
    def run(
        self,
        *,
        steps: int | None = None,
        t_end: float | None = None,
        stop: Callable[[Simulation], bool] | None = None,
    ) -> list[StepRecord]:
        """Advance until a step count, an end time or a stop rule is reached.

        The run stops after ``steps`` more steps, at ``t_end``, or when
        ``stop(sim)`` returns True, whichever comes first.  On SIGINT (Ctrl-C)
        or SIGTERM it stops after the step in progress (a second signal
        abandons that step), writes a checkpoint (with a ``checkpoint_dir``) and
        raises :class:`~skfem_npfem.errors.RunInterrupted`.

        Returns
        -------
        list of StepRecord
            All records of the run so far.
        """
        if steps is None and t_end is None and stop is None:
            raise ParameterError("steps", None, "give steps, t_end or a stop rule")
        if self.step == 0 and self.writer is not None and not self.writer.entries:
            # The initial state, with the mesh the first step will be built on.
            active, local_t = mesh_particles(self.mesh_source, self.particles)
            self.write_output(active[local_t].T, active)
        n_target = None if steps is None else self.step + int(steps)
        progress = Progress(
            bool(self.progress), n_target, t_end, self.progress_interval
        )
        first = (self.step, self.time)
        guard = SignalGuard()
        try:
            with guard:
                self._loop(n_target, t_end, stop, progress, first, guard)
        finally:
            progress.close()
        return self.records

    def _loop(self, n_target, t_end, stop, progress, first, guard) -> None:
        """The steps of :meth:`run`; stops at a signal after the step."""
        while True:
            if n_target is not None and self.step >= n_target:
                break
            if t_end is not None and self.time >= t_end * (1 - 1e-12):
                break
            if stop is not None and self.records and stop(self):
                break  # a resumed run that had already stopped
            dt = self.dt
            if t_end is not None and t_end - self.time < dt * (1 - 1e-9):
                # Land on t_end, but never shorten a step by round-off only.
                dt = t_end - self.time
            try:
                last = self._step_once(dt, n_target, t_end, stop, guard)
            except AbandonStep:
                self._interrupted(guard.signum, abandoned=True)
            progress.update(
                self.records[-1], self.time, *first, stopped=self.stopped_by
            )
            if last:
                break
            if guard.signum is not None:
                self._interrupted(guard.signum)

    def _interrupted(self, signum: int | None, abandoned: bool = False) -> None:
        """Checkpoint and write the last finished step; raise RunInterrupted.

        The step is written to the result series even off the output schedule,
        so the state a run stopped in can be opened in ParaView; a resumed run
        keeps it and continues the schedule.
        """
        path = self._last_checkpoint.get(self.step)
        if path is None:
            path = self.save_checkpoint()
        self._write_last_finished_step()
        raise RunInterrupted(
            signal.SIGINT if signum is None else signum,
            self.step,
            self.time,
            path,
            abandoned,
        )

    def _step_once(
        self,
        dt: float,
        n_target: int | None,
        t_end: float | None,
        stop: Callable[[Simulation], bool] | None,
        guard: SignalGuard | None = None,
    ) -> bool:
        """One step with its output, callbacks and checkpoint; True: stop now.

        The step's :class:`~skfem_npfem.step.stages.Step` lives only here: the
        run keeps its record.
        """
        if guard is not None:
            guard.in_step = True  # a second signal abandons this step
        new, result = self._try_step(dt)
        if guard is not None:
            guard.in_step = False
        rec = result.record
        self.particles = new
        self.step += 1
        self.state = result.state
        rec.step, rec.time = self.step, self.time
        v0 = self.records[0].mesh_volume if self.records else rec.mesh_volume
        rec.volume_change = rec.mesh_volume / v0 - 1.0 if v0 > 0 else 0.0
        self.records.append(rec)
        self.last_record = rec
        self.penetration_check(self, rec)
        last = (n_target is not None and self.step >= n_target) or (
            t_end is not None and self.time >= t_end * (1 - 1e-12)
        )
        t_out = time.perf_counter()
        # Every callback sees every step (a list, not a short-circuiting any()),
        # and the stop decision comes before the output: the step a stop rule
        # ends on (a deposit at rest) is the last one written, as for the others.
        stops = [bool(cb(self, new, result)) for cb in self.callbacks]
        by_rule = stop is not None and bool(stop(self))
        stop_now = any(stops) or by_rule
        self.stopped_by = None
        if stop_now and not last:  # ended before its step count or end time
            self.stopped_by = (
                getattr(stop, "label", "stop rule met") if by_rule else "callback"
            )
        if self.writer is not None and (
            self.step % self.output_every == 0 or last or stop_now
        ):
            self.write_output(result.cells, result.active)
        if self.checkpoint_every and (
            self.step % self.checkpoint_every == 0 or stop_now or last
        ):
            self.save_checkpoint()
        self.after_output(self)
        rec.timings["output"] = time.perf_counter() - t_out
        return stop_now

    def _try_step(self, dt: float) -> tuple[Particles, Step]:
        retries = 0
        while True:
            try:
                new, result = self._advance(dt)
            except SolverError as err:
                if not self.adaptive or dt / 2 < self.dt_min:
                    saved = self.save_checkpoint()
                    self._write_last_finished_step()
                    # Keep the solver's own advice (e.g. "use displacement
                    # control" for a static overload) and add the loop's context.
                    advice = str(err).split("; ", 1)[1] if "; " in str(err) else ""
                    unit = " s" if self.model.mode == "dynamic" else " (load step)"
                    where = f"dt={dt:g}{unit}" + (
                        f" (floor {self.dt_min:g} s)" if self.adaptive else ""
                    )
                    if saved is not None and self.step:  # step 0: nothing to keep
                        where += f"; results up to step {self.step} are on disk"
                    raise SolverError(
                        err.status,
                        self.step + 1,
                        err.iterations,
                        "; ".join(s for s in (advice, where) if s),
                    ) from err
                dt /= 2.0
                retries += 1
                self._successes = 0
                continue
            rec = result.record
            rec.retries = retries
            if self.adaptive:
                self._successes += 1
                if retries:
                    self.dt = dt
                elif self._successes >= self.grow_after and self.dt < self.dt_max:
                    self.dt = min(2 * self.dt, self.dt_max)
                    self._successes = 0
            if self.max_displacement is not None:
                start = (self.refiner or self).particles  # what the step moved
                self.dt, rec.extra["max_displacement_ratio"] = next_dt(
                    start.x, new, rec, dt, self.max_displacement, self
                )
                if retries:  # do not grow straight after a failure
                    self.dt = min(self.dt, dt)
            return new, result

    def _write_last_finished_step(self) -> None:
        """Write the last finished step if the output schedule skipped it.

        A run a solver failure or a signal stops is left with its final state
        in ParaView too, on the mesh the next step would be built on; a
        remesh that fails as well leaves the written steps as they are.
        """
        if self.writer is None or any(
            s == self.step for s, _, _ in self.writer.entries
        ):
            return
        if self.particles.spacing is not None:  # a refined run's alpha test
            self.mesh_source.spacing = self.particles.spacing
        try:
            active, local_t = mesh_particles(self.mesh_source, self.particles)
        except ParameterError:
            return
        self.write_output(active[local_t].T, active)

    def _advance(self, dt: float) -> tuple[Particles, Step]:
        method, p, src = self.stepper or advance, self.particles, self.mesh_source
        if (refine := self.refiner) is not None:  # new particles come last
            p = refine(p, src, self.model, self.state.time)
        new, out = method(p, self.model, dt, src, step=self.step + 1, start=self.state)
        out.record.extra.update(refine.record() if refine is not None else {})
        return new, out

    def summary(self) -> dict[str, Any]:
        """Solver statistics of the run (steps, iterations, time per phase).

        :func:`~skfem_npfem.run.statistics.run_statistics` of its records.
        ``peak_memory_mb`` is the run's, not only this process's: a run
        continued from a checkpoint reports the larger of its own peak and the
        one the checkpoint recorded of the processes before.
        """
        return run_statistics(
            self.records,
            self.time,
            self.particles.n,
            self.initial["mass"],
            self._peak_memory_before,
        )
