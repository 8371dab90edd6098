"""Particles to mesh: where each step's P1 mesh and its smoothing cells come from.

* :mod:`.sources` -- mesh sources: :class:`FixedMesh` (a mesh that does not change)
  and :class:`AlphaShapeMesher` (Delaunay triangulation of the particles and the
  alpha-shape test), free surface and main body;
* :mod:`.delaunay` -- the Delaunay triangulation, alpha shape and element quality;
* :mod:`.surface` -- boundary facets and free-surface particles;
* :mod:`.smoothing` -- nodal integration: smoothing cells and the smoothed strain
  operator ``G`` from scikit-fem's P1 gradients;
* :mod:`.axisymmetric` -- the same for the (r, z) half-section of a body of
  revolution, with the hoop strain;
* :mod:`.operators` -- the strain operator of a step's mesh (plane or
  axisymmetric) and the particle spacing;
* :mod:`.geometry` -- the tangents of unit normals (contact rows, rigid bodies);
* :mod:`.regions` -- cross-sections from polygons: checked regions, their
  thickness, particles filling them and their mesh;
* :mod:`.section_file` -- the JSON file of a cross-section, read and checked
  (every error names its key), and its implausible values;
* :mod:`.section_water` -- a section's phreatic line and seepage heads;
* :mod:`.section_mesh` -- a section drawn as a mesh file (gmsh): its regions'
  outlines and named lines.
"""
