"""Which library code produced a result: source hash and git commit.

Long sweeps (demos, benchmarks) store :func:`source_sha1` with every result, at
its start and end, so that a sweep run across a code change shows up.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
from pathlib import Path

__all__ = ["PACKAGE_DIR", "git", "source_sha1"]

#: The folder of the installed ``skfem_npfem`` package.
PACKAGE_DIR = Path(__file__).resolve().parents[1]


def source_sha1(relative_to: str | os.PathLike | None = None) -> str:
    """SHA-1 (12 hex digits) of the package's ``*.py`` files, names and contents.

    File names enter the hash relative to ``relative_to`` (default: the package
    folder itself).

    Examples
    --------
    >>> len(source_sha1()), source_sha1() == source_sha1(PACKAGE_DIR)
    (12, True)
    """
    base = PACKAGE_DIR if relative_to is None else Path(relative_to).resolve()
    h = hashlib.sha1()
    for f in sorted(PACKAGE_DIR.rglob("*.py")):
        h.update(str(f.relative_to(base)).encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:12]


def git(*args: str, timeout: float = 30.0) -> str | None:
    """Stdout of a read-only ``git`` command in the package's checkout.

    Parameters
    ----------
    *args : str
        The git arguments, e.g. ``"rev-parse", "HEAD"``.
    timeout : float
        Seconds before git is given up.

    Returns
    -------
    str or None
        Its stdout, or None when git is missing or timed out.
    """
    # No optional locks: `git status` must not even refresh the index.
    env = {**os.environ, "GIT_OPTIONAL_LOCKS": "0"}
    try:
        return subprocess.run(
            ["git", *args],
            cwd=PACKAGE_DIR.parent,
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout,
        ).stdout
    except (OSError, subprocess.SubprocessError):
        return None
