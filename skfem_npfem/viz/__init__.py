"""All drawing.

Result pictures (:mod:`.plot`), the figures of a step
(:mod:`.figures`), pyvista rendering (:mod:`.render`) and what each scene puts in a
picture (:mod:`.scenery`).  Importing it loads no plotting library.
"""
