"""``python -m skfem_npfem`` runs the same CLI as ``skfem-npfem``."""

from .cli import main

raise SystemExit(main())
