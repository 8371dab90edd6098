"""Old import paths of moved modules, kept working for one release."""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import warnings
from types import ModuleType


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Serve ``package.old`` as the module ``package.new`` (the same object)."""

    def __init__(self, package: str, moved: dict[str, str]) -> None:
        self.targets = {f"{package}.{o}": f"{package}.{n}" for o, n in moved.items()}
        self._specs: dict[str, importlib.machinery.ModuleSpec] = {}

    def find_spec(self, fullname, path=None, target=None):
        if fullname not in self.targets:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec) -> ModuleType:
        new = self.targets[spec.name]
        warnings.warn(
            f"{spec.name} moved to {new}; the old path will be removed in the "
            "next release (the public names of the package itself stay)",
            DeprecationWarning,
            stacklevel=2,
        )
        module = importlib.import_module(new)
        self._specs[new] = module.__spec__
        return module

    def exec_module(self, module: ModuleType) -> None:
        # The import system gave the module the alias's spec: give it back its own.
        module.__spec__ = self._specs[module.__name__]


def install_aliases(package: str, moved: dict[str, str]) -> None:
    """Let ``import package.OLD`` find ``package.NEW`` for every pair of ``moved``.

    Parameters
    ----------
    package : str
        The package's name.
    moved : dict
        Old module name (relative to ``package``) -> its new dotted path.
    """
    if not any(isinstance(f, _Alias) for f in sys.meta_path):
        sys.meta_path.append(_Alias(package, moved))
