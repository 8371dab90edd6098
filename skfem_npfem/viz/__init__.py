"""All drawing (the ``viz`` extra).

* :mod:`.plot` -- the pictures of a result folder (``skfem-npfem plot``);
* :mod:`.loading` -- reading a folder's steps for them; :mod:`.snapshots` --
  which steps a picture shows and how their times are named; :mod:`.colours`
  -- one colour range per field over all steps;
* :mod:`.figures` -- the 2D figures of a step (matplotlib);
  :mod:`.render` -- the pyvista renderer (3D); :mod:`.animation` -- GIF and
  MP4 from the renderer's frames;
* :mod:`.scenery` -- what a scene's scenery puts in a picture (floor, walls,
  outline, labels); :mod:`.mechanism` -- a limit analysis's collapse
  mechanism.

Importing it loads no plotting library.
"""
