"""A cross-section from a mesh file: the same regions as the JSON polygons.

The two-layer section of the slope tutorial (a clay layer 12 m x 1 m, a sand
embankment 3 m high on it) is meshed, written as gmsh 2.2 and 4.1 (ASCII and
binary) with meshio, and read back through a JSON file that names the mesh:
its regions must be the polygons of the JSON form, whose areas are 12 m^2 and
(7.5 + 3) / 2 x 3 = 15.75 m^2.  Two tiny files in the format gmsh writes
(``tests/data/section_square_v22.msh`` and ``..._v41.msh``: a 2 m x 1 m
square of two triangles, surface group ``soil``, line group ``top``) check
each format read independently of meshio's writer.
"""

from __future__ import annotations

import json
from pathlib import Path

import meshio
import numpy as np
import pytest

from skfem_npfem.errors import ParameterError
from skfem_npfem.mesh.regions import Region, fill_regions, point_in_polygon
from skfem_npfem.mesh.section_file import read_cross_section

DATA = Path(__file__).resolve().parents[1] / "data"
CLAY = np.array([[0, 0], [12, 0], [12, 1], [0, 1]], float)
SAND = np.array([[0, 1], [7.5, 1], [3, 4], [0, 4]], float)
MATERIALS = {
    "clay": {"c": 30000, "phi": 0, "rho": 1940},
    "sand": {"c": 0, "phi": 35, "rho": 1835},
}
#: Writers: (meshio format, binary).
FORMATS = {"2.2": ("gmsh22", False), "4.1": ("gmsh", False), "4.1-bin": ("gmsh", True)}


def write_msh(path: Path, fmt: str, groups: dict | None = None) -> Path:
    """The two-layer section as a gmsh file: groups clay (1), sand (2), upstream.

    ``groups``: name -> (tag, dim) of the physical names (default: clay,
    sand, upstream).
    """
    pts, tri, _ = fill_regions([Region("clay", CLAY), Region("sand", SAND)], 0.5)
    tri = tri.T
    tag = np.where(point_in_polygon(pts[tri].mean(axis=1), SAND), 2, 1)
    left = np.flatnonzero((np.abs(pts[:, 0]) < 1e-9) & (pts[:, 1] > 1 - 1e-9))
    left = left[np.argsort(pts[left, 1])]
    seg = np.column_stack([left[:-1], left[1:]])
    dim_tags = np.zeros((len(pts), 2), int)
    dim_tags[tri.ravel()] = np.column_stack([np.full(tri.size, 2), np.repeat(tag, 3)])
    dim_tags[seg.ravel()] = [1, 3]
    cells = [("line", seg), ("triangle", tri[tag == 1]), ("triangle", tri[tag == 2])]
    phys = [np.full(len(c), t) for (_, c), t in zip(cells, (3, 1, 2), strict=True)]
    groups = groups or {"clay": (1, 2), "sand": (2, 2), "upstream": (3, 1)}
    mesh = meshio.Mesh(
        np.column_stack([pts, np.zeros(len(pts))]),
        cells,
        point_data={"gmsh:dim_tags": dim_tags},
        cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
        field_data={k: np.array(v) for k, v in groups.items()},
    )
    kind, binary = FORMATS[fmt]
    mesh.write(path, file_format=kind, binary=binary)
    return path


def write_json(folder: Path, mesh: str, **extra) -> Path:
    path = folder / "section.json"
    path.write_text(json.dumps({"mesh": mesh, "materials": MATERIALS, **extra}))
    return path


def _area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_mesh_section_gives_the_json_polygons(tmp_path, fmt):
    write_msh(tmp_path / "s.msh", fmt)
    sec = read_cross_section(write_json(tmp_path, "s.msh"))
    assert [r.material for r in sec.regions] == ["clay", "sand"]
    # The outlines start, as the JSON polygons do, at the lowest-leftmost vertex.
    assert np.array_equal(sec.regions[0].polygon, CLAY)
    assert np.array_equal(sec.regions[1].polygon, SAND)
    # Region areas against the analytic 12 and 15.75 m^2.
    assert abs(_area(sec.regions[0].polygon) - 12.0) < 1e-12
    assert abs(_area(sec.regions[1].polygon) - 15.75) < 1e-12
    # The particles and mesh of the mesh section are those of the JSON section.
    json_fill = fill_regions([Region("clay", CLAY), Region("sand", SAND)], 0.4)
    mesh_fill = fill_regions(sec.regions, 0.4)
    assert all(np.array_equal(u, v) for u, v in zip(json_fill, mesh_fill, strict=True))


@pytest.mark.parametrize("version", ["v22", "v41"])
def test_gmsh_files_of_both_versions(tmp_path, version):
    mesh = DATA / f"section_square_{version}.msh"
    sec = read_cross_section(
        write_json(tmp_path, str(mesh), materials={"soil": {"rho": 1800}}, water="top")
    )
    assert len(sec.regions) == 1 and sec.regions[0].material == "soil"
    assert np.array_equal(sec.regions[0].polygon, [[0, 0], [2, 0], [2, 1], [0, 1]])
    # The line group "top" named as the phreatic line: z = 1 over x in [0, 2].
    assert np.allclose(sec.water, [[0, 1], [2, 1]])


def _error(path: Path) -> ParameterError:
    with pytest.raises(ParameterError) as err:
        read_cross_section(path)
    return err.value


def test_group_without_material(tmp_path):
    write_msh(tmp_path / "s.msh", "2.2", {"clay": (1, 2), "gravel": (2, 2)})
    err = _error(write_json(tmp_path, "s.msh"))
    assert err.name == "mesh group 'gravel'" and "clay, sand" in str(err)


def test_group_left_out_of_regions(tmp_path):
    write_msh(tmp_path / "s.msh", "2.2")
    err = _error(
        write_json(tmp_path, "s.msh", regions=[{"group": "clay", "material": "clay"}])
    )
    assert err.name == "mesh group 'sand'"


def test_region_names_a_missing_group(tmp_path):
    write_msh(tmp_path / "s.msh", "2.2")
    regions = [
        {"group": "clay", "material": "clay"},
        {"group": "fill", "material": "sand"},
    ]
    err = _error(write_json(tmp_path, "s.msh", regions=regions))
    assert err.name == "regions[1].group" and "clay, sand" in str(err)


def test_mesh_without_triangles(tmp_path):
    mesh = meshio.Mesh(
        np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), [("line", [[0, 1]])]
    )
    mesh.write(tmp_path / "s.msh", file_format="gmsh22", binary=False)
    err = _error(write_json(tmp_path, "s.msh"))
    assert err.name == "mesh" and "triangles" in str(err)


def test_triangles_without_physical_group(tmp_path):
    text = (DATA / "section_square_v22.msh").read_text()
    # Zero tags on every element: no physical group.
    body = "3\n1 1 0 3 4\n2 2 0 1 2 3\n3 2 0 1 3 4\n"
    start = text.index("$Elements\n") + len("$Elements\n")
    (tmp_path / "s.msh").write_text(text[:start] + body + "$EndElements\n")
    err = _error(write_json(tmp_path, "s.msh"))
    assert err.name == "mesh" and "physical surface group" in str(err)


@pytest.mark.parametrize("content", [None, "not a mesh\n"])
def test_unreadable_mesh(tmp_path, content):
    if content is not None:
        (tmp_path / "s.msh").write_text(content)
    err = _error(write_json(tmp_path, "s.msh"))
    assert err.name == "mesh" and "meshio" in str(err)


def test_region_with_a_hole(tmp_path):
    # A ring: the outer square's triangles minus the middle cell.
    g = np.stack(np.meshgrid(np.arange(4.0), np.arange(4.0)), -1).reshape(-1, 2)
    tri = []
    for i in range(3):
        for j in range(3):
            if (i, j) != (1, 1):
                a = 4 * j + i
                tri += [[a, a + 1, a + 5], [a, a + 5, a + 4]]
    mesh = meshio.Mesh(
        np.column_stack([g, np.zeros(len(g))]),
        [("triangle", np.array(tri))],
        cell_data={
            "gmsh:physical": [np.ones(len(tri), int)],
            "gmsh:geometrical": [np.ones(len(tri), int)],
        },
        field_data={"clay": np.array([1, 2])},
    )
    mesh.write(tmp_path / "s.msh", file_format="gmsh22", binary=False)
    err = _error(write_json(tmp_path, "s.msh"))
    assert err.name == "mesh group 'clay'" and "hole" in str(err)


def _one_group(tmp_path, points, triangles) -> Path:
    mesh = meshio.Mesh(
        points,
        [("triangle", np.array(triangles))],
        cell_data={"gmsh:physical": [np.ones(len(triangles), int)]},
        field_data={"clay": np.array([1, 2])},
    )
    mesh.write(tmp_path / "s.msh", file_format="gmsh22", binary=False)
    return write_json(tmp_path, "s.msh")


def test_pieces_touching_at_a_node(tmp_path):
    # Two triangles of one group that share only the node (1, 1).
    pts = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [2, 1, 0], [2, 2, 0], [1, 2, 0]]
    err = _error(_one_group(tmp_path, np.array(pts, float), [[0, 1, 2], [2, 3, 4]]))
    assert err.name == "mesh group 'clay'" and "node" in str(err)


def test_mesh_out_of_the_plane(tmp_path):
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 1]], float)  # in x-z
    err = _error(_one_group(tmp_path, pts, [[0, 1, 2]]))
    assert err.name == "mesh" and "plane" in str(err)
