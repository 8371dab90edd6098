"""Result output (VTU + PVD time series) and restart checkpoints.

Results
-------
:class:`ResultWriter` writes one ``<basename>_<step:06d>.vtu`` file per output
step, because particle meshes change topology every step, plus a ParaView
``<basename>.pvd`` collection and a ``<basename>.vtu.series`` JSON file that
list every step with its physical time. Every file is written to a hidden
temporary file in the same folder and moved into place with :func:`os.replace`,
so a crash never leaves a half-written file under a final name.

Checkpoints
-----------
A checkpoint is one uncompressed NumPy ``.npz`` file, usually named
``checkpoint_<step:06d>.npz`` (see :func:`checkpoint_path`). Format version
``"skfem-npfem-checkpoint/1"`` contains the keys

``__format__``
    0-d string array holding the format version.
``__meta__``
    0-d string array holding a JSON object. The simulation loop stores
    ``step`` (int), ``time`` (float), ``dt`` (float), ``scene`` (str) and
    ``parameters`` (dict of JSON values).
any other key
    One particle array each, first dimension = number of particles, for example
    ``x`` and ``v`` and ``a`` (N, d) positions, velocities and accelerations,
    ``stress`` (N, ...) Cauchy stress, ``eps_p`` (N,) equivalent plastic strain,
    ``mass`` (N,) and ``material`` (N,) integer material ids.

Arrays must be numeric or bool (no object arrays) and finite.
"""

from __future__ import annotations

import io
import json
import operator
import os
import re
import tempfile
import xml.etree.ElementTree as ET
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from zipfile import BadZipFile

import meshio
import numpy as np

from skfem_npfem.errors import CheckpointError, ParameterError

__all__ = [
    "CHECKPOINT_FORMAT",
    "ResultWriter",
    "checkpoint_path",
    "latest_checkpoint",
    "load_checkpoint",
    "read_pvd",
    "read_step",
    "save_checkpoint",
]

CHECKPOINT_FORMAT = "skfem-npfem-checkpoint/1"
_KNOWN_FORMATS = (CHECKPOINT_FORMAT,)
_BAD_NAME = re.compile(r"[<>&\"']")
# zipfile raises NotImplementedError (unknown compression/version) and
# RuntimeError (encrypted flag) on corrupted headers.
_LOAD_ERRORS = (
    OSError,
    ValueError,
    TypeError,
    EOFError,
    BadZipFile,
    zlib.error,
    NotImplementedError,
    RuntimeError,
)


def _step(name: str, value: Any) -> int:
    """Return ``value`` as an int >= 0 or raise ParameterError."""
    try:
        step = operator.index(value)
    except TypeError:
        step = -1
    if step < 0:
        raise ParameterError(name, value, "an integer >= 0")
    return step


def _write_synced(path: Path, data: bytes) -> None:
    with open(path, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())


def _atomic_write(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a synced temporary file."""
    tmp = path.with_name(f".tmp_{path.name}")
    try:
        _write_synced(tmp, data)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


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
    ) -> None:
        self.out_dir = Path(out_dir)
        if not basename or _BAD_NAME.search(basename) or "/" in basename:
            raise ParameterError("basename", basename, "a plain file-name prefix")
        self.basename = basename
        try:
            self.out_dir.mkdir(parents=True, exist_ok=True)
            fd, probe = tempfile.mkstemp(dir=self.out_dir, prefix=".tmp_probe_")
            os.close(fd)
            os.unlink(probe)
        except OSError as exc:
            msg = f"a writable directory ({exc})"
            raise ParameterError("out", str(out_dir), msg) from exc
        self.pvd_path = self.out_dir / f"{basename}.pvd"
        self.series_path = self.out_dir / f"{basename}.vtu.series"
        self._pattern = re.compile(rf"{re.escape(basename)}_(\d+)\.vtu")
        self._entries: dict[int, tuple[float, str]] = {}
        stray = re.compile(
            rf"\.tmp_{re.escape(basename)}(_\d+\.vtu|\.pvd|\.vtu\.series)"
        )
        for f in self.out_dir.iterdir():
            if stray.fullmatch(f.name):
                f.unlink(missing_ok=True)
        if resume_after_step is not None:
            resume_after_step = _step("resume_after_step", resume_after_step)
            if self.pvd_path.exists():
                for time, file in read_pvd(self.pvd_path):
                    m = self._pattern.fullmatch(file.name)
                    if m and int(m[1]) <= resume_after_step and file.exists():
                        self._entries[int(m[1])] = (time, file.name)
        for f in self.out_dir.glob(f"{basename}_*.vtu"):
            m = self._pattern.fullmatch(f.name)
            if m and (resume_after_step is None or int(m[1]) > resume_after_step):
                f.unlink()
        self._write_index()

    @property
    def entries(self) -> list[tuple[int, float, str]]:
        """List of ``(step, time, filename)`` written so far, sorted by step."""
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
            Physical time of the step.
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
        step, time = _step("step", step), float(time)
        if not np.isfinite(time):
            raise ParameterError("time", time, "a finite number")
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
        tmp = final.with_name(f".tmp_{final.name}")
        try:
            meshio.write(tmp, meshio.Mesh(p3, blocks, point_data=pdata), "vtu")
            text = tmp.read_bytes().replace(
                b"<UnstructuredGrid>\n", b"<UnstructuredGrid>\n" + fxml, 1
            )
            _write_synced(tmp, text)
            os.replace(tmp, final)
        finally:
            tmp.unlink(missing_ok=True)
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
        _atomic_write(self.pvd_path, xml + b"\n")
        series = {"file-series-version": "1.0", "files": files}
        _atomic_write(self.series_path, json.dumps(series, indent=1).encode())


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
        return meshio.read(path, file_format="vtu")
    except (OSError, ValueError, ET.ParseError, meshio.ReadError) as exc:
        raise CheckpointError(f"{path}: unreadable VTU file ({exc})") from exc


def checkpoint_path(folder: str | os.PathLike, step: int) -> Path:
    """Return ``folder / f"checkpoint_{step:06d}.npz"``."""
    return Path(folder) / f"checkpoint_{_step('step', step):06d}.npz"


def latest_checkpoint(
    folder: str | os.PathLike, pattern: str = "checkpoint_*.npz"
) -> Path | None:
    """Return the checkpoint in ``folder`` with the largest step number, or None.

    The step number is the last group of digits in the file name.
    """
    best: tuple[int, Path] | None = None
    for f in Path(folder).glob(pattern):
        digits = re.findall(r"\d+", f.name.removesuffix(".npz"))
        if f.is_file() and digits and (best is None or int(digits[-1]) > best[0]):
            best = (int(digits[-1]), f)
    return None if best is None else best[1]


def _json_default(obj: object) -> object:
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"{type(obj).__name__} is not JSON serializable")


def save_checkpoint(
    path: str | os.PathLike, arrays: Mapping[str, np.ndarray], meta: Mapping
) -> Path:
    """Write a checkpoint atomically (format described in the module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        Target ``.npz`` file; its folder must exist.
    arrays : mapping of str to numpy.ndarray
        Finite numeric or bool arrays; names must not start with ``__``.
    meta : mapping
        JSON-serializable metadata (numpy scalars and arrays are converted).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    data: dict[str, np.ndarray] = {}
    for name, arr in arrays.items():
        a = np.asarray(arr)
        if (
            not isinstance(name, str)
            or name.startswith("__")
            or a.dtype.kind not in "biufc"
        ):
            raise ParameterError(f"arrays[{name!r}]", a.dtype, "numeric, not __name")
        if a.dtype.kind in "fc" and not np.isfinite(a).all():
            raise ParameterError(f"arrays[{name!r}]", "NaN/inf", "finite values only")
        data[name] = a
    try:
        meta_json = json.dumps(dict(meta), default=_json_default, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ParameterError("meta", meta, f"JSON-serializable ({exc})") from exc
    data["__meta__"] = np.array(meta_json)
    data["__format__"] = np.array(CHECKPOINT_FORMAT)
    buf = io.BytesIO()
    np.savez(buf, **data)
    _atomic_write(path, buf.getvalue())
    return path


def load_checkpoint(path: str | os.PathLike) -> tuple[dict[str, np.ndarray], dict]:
    """Load and validate a checkpoint written by :func:`save_checkpoint`.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.npz`` checkpoint.

    Returns
    -------
    arrays : dict of str to numpy.ndarray
        The particle arrays (without the ``__format__``/``__meta__`` keys).
    meta : dict
        The decoded metadata.

    Raises
    ------
    CheckpointError
        If the file is missing, truncated, not an npz file, of an unknown
        format version, has corrupt metadata or contains NaN/inf.
    """
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"checkpoint {path}: file does not exist")
    try:
        z = np.load(path, allow_pickle=False)
        if not isinstance(z, np.lib.npyio.NpzFile):
            raise TypeError("a single .npy array")
        with z:
            data = {k: z[k] for k in z.files}
    except _LOAD_ERRORS as exc:
        raise CheckpointError(
            f"checkpoint {path}: truncated or not an npz file ({exc})"
        ) from exc
    fmt = data.pop("__format__", None)
    if fmt is None:
        raise CheckpointError(f"checkpoint {path}: no __format__ key (not ours?)")
    if str(fmt) not in _KNOWN_FORMATS:
        raise CheckpointError(
            f"checkpoint {path}: unknown format version {str(fmt)!r}, "
            f"known: {', '.join(_KNOWN_FORMATS)}"
        )
    try:
        meta = json.loads(str(data.pop("__meta__")))
        if not isinstance(meta, dict):
            raise TypeError("not a JSON object")
    except (KeyError, ValueError, TypeError) as exc:
        raise CheckpointError(f"checkpoint {path}: bad metadata ({exc})") from exc
    for name, a in data.items():
        if a.dtype.kind in "fc" and not np.isfinite(a).all():
            raise CheckpointError(f"checkpoint {path}: array {name!r} has NaN/inf")
    return data, meta
