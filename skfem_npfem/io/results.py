"""Result output: one VTU file per step plus ``.pvd`` and ``.vtu.series`` indexes.

:class:`ResultWriter` writes one ``<basename>_<step:06d>.vtu`` file per output
step, because particle meshes change topology every step, plus a ParaView
``<basename>.pvd`` collection and a ``<basename>.vtu.series`` JSON file that
list every step with its physical time.  Every file goes through the atomic
writer of :mod:`skfem_npfem.io.files`.  :func:`read_pvd` and :func:`read_step`
read them back, and :func:`step_time` reads a step's time from its own file
(its ``TimeValue`` field data), so an index that was lost is rebuilt from the
VTU files on disk when a run is resumed.
"""

from __future__ import annotations

import operator
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import meshio
import numpy as np

from ..errors import CheckpointError, ParameterError, warn_user
from .files import atomic_path, check_writable_dir, write_bytes, write_json

__all__ = [
    "TIME_DIGITS",
    "ResultWriter",
    "clean_time",
    "read_pvd",
    "read_step",
    "step_number",
    "step_time",
    "water_point_data",
]

_BAD_NAME = re.compile(r"[<>&\"']")


def step_number(name: str, value: Any) -> int:
    """Return ``value`` as an int >= 0 or raise ParameterError naming ``name``."""
    try:
        step = operator.index(value)
    except TypeError:
        step = -1
    if step < 0:
        raise ParameterError(name, value, "an integer >= 0")
    return step


#: Significant digits of the step times written to the files.
TIME_DIGITS = 12


def clean_time(time: float) -> float:
    """A step time as written to the files: rounded to :data:`TIME_DIGITS` digits.

    A run's time is the sum of its step lengths, which carries round-off in
    its last digits (``0.1 + 0.1 + 0.1 = 0.30000000000000004``); the files
    show the time those digits stand for.

    Examples
    --------
    >>> clean_time(0.1 + 0.1 + 0.1), clean_time(60 * 0.005), clean_time(1.5e-11)
    (0.3, 0.3, 1.5e-11)
    """
    return float(f"{time:.{TIME_DIGITS}g}")


def water_point_data(
    particles: Any,
    model: Any,
    active: np.ndarray | None = None,
    cells: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """The point data of a wet result: pore pressures, effective and total stress.

    Parameters
    ----------
    particles : Particles
        Their ``stress`` (full Voigt, normal components ``xx, yy, zz`` first,
        tension positive, Pa) is the *effective* stress when there is water;
        ``pore_pressure`` (compression positive) and ``excess_pore_pressure``
        are None before the first step.
    model : Model
        Its ``water`` (None: a dry model) and ``gravity``: the static pore
        pressure of particles that carry none yet (the initial state).
    active : numpy.ndarray, optional
        Particles in the mesh (indices or a boolean mask); the static
        pressure of the initial state is given to these only (all if None),
        as a step gives it.
    cells : numpy.ndarray, optional
        The mesh, (ne, 3) particle indices: a seepage's static pressure is
        solved on it.

    Returns
    -------
    dict
        Empty for a dry model whose particles carry no pore pressure; else
        ``pore_pressure``, ``excess_pore_pressure`` (zero when the particles
        carry none), ``effective_stress`` (the particles' stress) and
        ``total_stress`` (the effective stress less the pore pressure on the
        normal components: Terzaghi's principle, tension positive), Pa.
    """
    water, pore = getattr(model, "water", None), particles.pore_pressure
    if pore is None and water is None:
        return {}
    sig = np.asarray(particles.stress, dtype=float)
    if pore is None:
        # A seepage is Darcy's problem on the mesh, conductivity by material.
        t = None if cells is None else np.asarray(cells).T
        seepage = getattr(water, "seepage", None) is not None
        mesh = (t, particles.material) if seepage else ()
        pore = water.static_pressure(particles.x, model.gravity, *mesh)
        if active is not None:
            mask = np.zeros(len(pore), dtype=bool)
            mask[active] = True
            pore = np.where(mask, pore, 0.0)
    pore = np.asarray(pore, dtype=float)
    excess = particles.excess_pore_pressure
    total = sig.copy()
    total[:, :3] -= pore[:, None]
    return {
        "pore_pressure": pore,
        "excess_pore_pressure": np.zeros_like(pore) if excess is None else excess,
        "effective_stress": sig.copy(),
        "total_stress": total,
    }


def _field_data_xml(field_data: Mapping[str, Any]) -> bytes:
    """Return a VTK ``<FieldData>`` element with ASCII arrays."""
    parts = ["<FieldData>\n"]
    for name, value in field_data.items():
        a = np.asarray(value).ravel()
        if not isinstance(name, str) or _BAD_NAME.search(name) or not name:
            raise ParameterError("field_data name", name, "a non-empty plain string")
        if a.dtype.kind not in "biuf" or not np.isfinite(a.astype(float)).all():
            raise ParameterError(f"field_data[{name!r}]", value, "finite numbers")
        a = a.astype(np.float64 if a.dtype.kind == "f" else np.int64)
        vtk = "Float64" if a.dtype.kind == "f" else "Int64"
        text = " ".join(repr(v) for v in a.tolist())
        parts.append(
            f'<DataArray type="{vtk}" Name="{name}" NumberOfTuples="{a.size}" '
            f'format="ascii">\n{text}\n</DataArray>\n'
        )
    parts.append("</FieldData>\n")
    return "".join(parts).encode()


class ResultWriter:
    """Write a VTU file per step plus ``.pvd`` and ``.vtu.series`` indexes.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Output folder, created if needed.
    basename : str, default "result"
        Prefix of every file written.
    resume_after_step : int or None, default None
        If given, keep the existing steps ``<= resume_after_step`` listed in the
        ``.pvd`` and delete the VTU files of later steps. If None, remove stale
        ``<basename>_*.vtu`` files and start an empty collection.
    defer : bool, default False
        True: only check the folder now and leave its files alone until
        :meth:`open` (called by the first :meth:`write` or :attr:`entries` at
        the latest), so that a run can finish every check before it touches
        the folder.

    Raises
    ------
    ParameterError
        If ``out_dir`` cannot be created or is not writable.
    CheckpointError
        If resuming and the existing ``.pvd`` is corrupt.
    """

    def __init__(
        self,
        out_dir: str | os.PathLike,
        basename: str = "result",
        resume_after_step: int | None = None,
        *,
        defer: bool = False,
    ) -> None:
        self.out_dir = Path(out_dir)
        if not basename or _BAD_NAME.search(basename) or "/" in basename:
            raise ParameterError("basename", basename, "a plain file-name prefix")
        self.basename = basename
        check_writable_dir("out", self.out_dir, create=not defer)
        self.pvd_path = self.out_dir / f"{basename}.pvd"
        self.series_path = self.out_dir / f"{basename}.vtu.series"
        self._pattern = re.compile(rf"{re.escape(basename)}_(\d+)\.vtu")
        self._entries: dict[int, tuple[float, str]] = {}
        if resume_after_step is not None:
            resume_after_step = step_number("resume_after_step", resume_after_step)
        self._resume_after_step = resume_after_step
        self._opened = False
        if not defer:
            self.open()

    def open(self) -> None:
        """Prepare the folder: remove stray temporaries and stale steps, index.

        Temporaries a killed writer left (``.tmp_<basename>...``) are removed;
        then either the steps after ``resume_after_step`` or all earlier steps
        are deleted, and the ``.pvd`` and ``.vtu.series`` indexes are written.
        Runs once; later calls do nothing.
        """
        if self._opened:
            return
        self._opened = True
        basename, last = self.basename, self._resume_after_step
        self.out_dir.mkdir(parents=True, exist_ok=True)
        stray = re.compile(
            rf"\.tmp_{re.escape(basename)}(_\d+\.vtu|\.pvd|\.vtu\.series)"
        )
        for f in self.out_dir.iterdir():
            if stray.fullmatch(f.name):
                f.unlink(missing_ok=True)
        if last is not None:
            self._entries = self._kept_steps(last)
        for f in self.out_dir.glob(f"{basename}_*.vtu"):
            m = self._pattern.fullmatch(f.name)
            if m and (last is None or int(m[1]) > last):
                f.unlink()
        self._write_index()

    def move_to(self, out_dir: str | os.PathLike) -> None:
        """Write the next steps and the indexes into ``out_dir`` instead.

        For a run whose files were moved there (a staged run that committed,
        :class:`~skfem_npfem.io.run_folder.RunFolder`); the steps written so
        far are listed by name, so the indexes stay valid.
        """
        self.out_dir = Path(out_dir)
        self.pvd_path = self.out_dir / self.pvd_path.name
        self.series_path = self.out_dir / self.series_path.name

    def _kept_steps(self, last: int) -> dict[int, tuple[float, str]]:
        """Steps ``<= last`` to keep on resuming: the index plus the files on disk.

        The ``.pvd`` gives the times of the steps it lists; a step file on disk
        that it does not list (the index was lost, damaged or older) is added
        with the time stored in the file.  A step file that cannot be read is
        left out with a warning.
        """
        kept: dict[int, tuple[float, str]] = {}
        if self.pvd_path.exists():
            try:
                listed = read_pvd(self.pvd_path)
            except CheckpointError as err:
                warn_user(f"{err}; rebuilding it from the VTU files")
                listed = []
            for time, file in listed:
                m = self._pattern.fullmatch(file.name)
                if m and int(m[1]) <= last and file.exists():
                    kept[int(m[1])] = (time, file.name)
        added, unreadable = 0, []
        for f in sorted(self.out_dir.glob(f"{self.basename}_*.vtu")):
            m = self._pattern.fullmatch(f.name)
            if not m or int(m[1]) > last or int(m[1]) in kept:
                continue
            try:
                kept[int(m[1])] = (step_time(f), f.name)
                added += 1
            except CheckpointError:
                unreadable.append(f.name)
        if added:
            warn_user(
                f"{self.pvd_path.name} did not list {added} step file(s) on disk; "
                "added them with the times stored in the files",
            )
        if unreadable:
            warn_user(
                f"left out {len(unreadable)} unreadable step file(s): "
                + ", ".join(unreadable[:5]),
            )
        return kept

    @property
    def entries(self) -> list[tuple[int, float, str]]:
        """List of ``(step, time, filename)`` written so far, sorted by step."""
        self.open()
        return [(s, t, f) for s, (t, f) in sorted(self._entries.items())]

    def write(
        self,
        step: int,
        time: float,
        points: np.ndarray,
        cells: np.ndarray | None,
        point_data: Mapping[str, np.ndarray],
        field_data: Mapping[str, Any] | None = None,
    ) -> Path:
        """Write one output step and update the ``.pvd`` and ``.vtu.series`` files.

        Parameters
        ----------
        step : int
            Step number (>= 0); an existing step with this number is replaced.
        time : float
            Physical time of the step (written rounded to :data:`TIME_DIGITS`
            significant digits, :func:`clean_time`).
        points : numpy.ndarray
            Particle positions, shape (N, d) with d in {2, 3}.
        cells : numpy.ndarray or None
            Triangles (d=2) or tetrahedra (d=3), shape (ne, d + 1). Tetrahedra
            are reoriented to positive volume. Particles in no cell are written
            as ``vertex`` cells.
        point_data : mapping of str to numpy.ndarray
            Finite arrays with first dimension N. (N, 2) vectors are padded to
            (N, 3), bool becomes uint8, arrays with ndim > 2 are reshaped to
            (N, -1) (e.g. a 3x3 tensor becomes 9 components).
        field_data : mapping, optional
            Numbers or numeric arrays stored flattened as VTK field data.
            ``TimeValue`` is always added with the step time.

        Returns
        -------
        pathlib.Path
            Path of the VTU file written.

        Raises
        ------
        ParameterError
            If an argument is malformed or a point-data array is not finite.
        """
        self.open()
        step, time = step_number("step", step), float(time)
        if not np.isfinite(time):
            raise ParameterError("time", time, "a finite number")
        time = clean_time(time)
        p = np.asarray(points, dtype=float)
        if p.ndim != 2 or p.shape[1] not in (2, 3) or not np.isfinite(p).all():
            raise ParameterError("points", p.shape, "a finite (N, 2) or (N, 3) array")
        n, d = p.shape
        p3 = np.hstack([p, np.zeros((n, 3 - d))])
        t = np.zeros((0, d + 1), dtype=np.int64) if cells is None else np.asarray(cells)
        t = t.reshape(0, d + 1) if t.size == 0 else t
        if (
            t.ndim != 2
            or t.shape[1] != d + 1
            or (t.size and (t.dtype.kind not in "iu" or t.min() < 0 or t.max() >= n))
        ):
            raise ParameterError(
                "cells", t.shape, f"an integer (ne, {d + 1}) array of indices < {n}"
            )
        t = t.astype(np.int64)
        if d == 3 and len(t):
            neg = np.linalg.det(p[t[:, 1:]] - p[t[:, :1]]) < 0
            t[np.ix_(neg, [2, 3])] = t[np.ix_(neg, [3, 2])]
        used = np.zeros(n, dtype=bool)
        used[t.ravel()] = True
        blocks = [("triangle" if d == 2 else "tetra", t)] if len(t) else []
        if not used.all():
            blocks.append(("vertex", np.flatnonzero(~used)[:, None]))
        pdata = {name: self._check_field(name, a, n) for name, a in point_data.items()}
        fxml = _field_data_xml({"TimeValue": time, **(field_data or {})})

        final = self.out_dir / f"{self.basename}_{step:06d}.vtu"
        with atomic_path(final) as tmp:
            meshio.write(tmp, meshio.Mesh(p3, blocks, point_data=pdata), "vtu")
            text = tmp.read_bytes().replace(
                b"<UnstructuredGrid>\n", b"<UnstructuredGrid>\n" + fxml, 1
            )
            tmp.write_bytes(text)
        self._entries[step] = (time, final.name)
        self._write_index()
        return final

    @staticmethod
    def _check_field(name: str, arr: np.ndarray, n: int) -> np.ndarray:
        if not isinstance(name, str) or not name or _BAD_NAME.search(name):
            raise ParameterError("point_data name", name, "a non-empty plain string")
        a = np.asarray(arr)
        key = f"point_data[{name!r}]"
        if a.dtype == bool:
            a = a.astype(np.uint8)
        if a.dtype.kind not in "iuf":
            raise ParameterError(key, a.dtype, "a numeric or bool array")
        if a.ndim == 0 or a.shape[0] != n:
            raise ParameterError(key, a.shape, f"an array with first dimension {n}")
        if a.dtype.kind == "f" and not np.isfinite(a).all():
            bad = int(np.count_nonzero(~np.isfinite(a)))
            raise ParameterError(key, f"{bad} NaN/inf values", "finite values only")
        if a.ndim > 2:
            a = a.reshape(n, -1)
        if a.ndim == 2 and a.shape[1] == 2:
            a = np.hstack([a, np.zeros((n, 1), dtype=a.dtype)])
        return a

    def _write_index(self) -> None:
        root = ET.Element(
            "VTKFile", type="Collection", version="0.1", byte_order="LittleEndian"
        )
        coll = ET.SubElement(root, "Collection")
        files = []
        for _, time, name in self.entries:
            attrs = {"timestep": repr(time), "group": "", "part": "0", "file": name}
            ET.SubElement(coll, "DataSet", attrs)
            files.append({"name": name, "time": time})
        ET.indent(root)
        xml = ET.tostring(root, encoding="utf-8", xml_declaration=True)
        write_bytes(self.pvd_path, xml + b"\n")
        series = {"file-series-version": "1.0", "files": files}
        write_json(self.series_path, series)


def read_pvd(path: str | os.PathLike) -> list[tuple[float, Path]]:
    """Read a ParaView ``.pvd`` collection.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.pvd`` file.

    Returns
    -------
    list of (float, pathlib.Path)
        ``(time, file)`` per data set in file order; relative file names are
        resolved against the folder of the ``.pvd``.

    Raises
    ------
    CheckpointError
        If the file is missing or is not a valid collection.
    """
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
        if root.tag != "VTKFile" or root.get("type") != "Collection":
            raise ValueError("root is not <VTKFile type='Collection'>")
        return [
            (float(ds.attrib["timestep"]), path.parent / ds.attrib["file"])
            for ds in root.iter("DataSet")
        ]
    except FileNotFoundError as exc:
        raise CheckpointError(f"{path}: PVD file does not exist") from exc
    except (OSError, ET.ParseError, KeyError, ValueError) as exc:
        raise CheckpointError(f"{path}: corrupt PVD collection ({exc})") from exc


def read_step(path: str | os.PathLike) -> meshio.Mesh:
    """Read one VTU step written by :class:`ResultWriter`.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.vtu`` file.

    Returns
    -------
    meshio.Mesh
        Points are 3-D; ``field_data["TimeValue"]`` holds the step time.
    """
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"{path}: VTU file does not exist")
    try:
        # The VTU reader itself: meshio.read() prints and calls sys.exit(1)
        # when a file cannot be parsed.
        return meshio.vtu.read(path)
    except (OSError, ValueError, EOFError, ET.ParseError, meshio.ReadError) as exc:
        why = str(exc) or type(exc).__name__
        raise CheckpointError(f"{path}: unreadable VTU file ({why})") from exc
    except SystemExit as exc:  # pragma: no cover - older meshio versions
        raise CheckpointError(f"{path}: unreadable VTU file") from exc


def step_time(path: str | os.PathLike) -> float:
    """The physical time stored in a VTU step (its ``TimeValue`` field data).

    Raises
    ------
    CheckpointError
        If the file cannot be read or holds no finite ``TimeValue``.
    """
    mesh = read_step(path)
    try:
        time = float(np.ravel(mesh.field_data["TimeValue"])[0])
        if not np.isfinite(time):
            raise ValueError(time)
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise CheckpointError(f"{path}: no finite TimeValue in the VTU file") from exc
    return time
