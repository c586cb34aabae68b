#!/usr/bin/env python3
"""Writes the seed corpus of the `read_3mf` fuzz target (fuzz/corpus/read_3mf/).

Run with the venv's Python (lib3mf is pinned in tools/requirements.txt):
- components-lib3mf.3mf, production-lib3mf.3mf: written by lib3mf, a components object placing
  a tetrahedron twice under a scaled build item; in the second the meshes sit in
  /3D/Objects/o.model, referenced by the production extension's p:path.
- inch-mirror-support.3mf: stored (uncompressed, so mutations reach the XML) with unit inch, a
  mirroring build item, a support object and a foreign element holding a <vertex>.
- cycle.3mf: refused, its components refer to each other.
"""
import pathlib
import zipfile

import lib3mf

OUT = pathlib.Path(__file__).resolve().parent.parent / "fuzz" / "corpus" / "read_3mf"
CORE = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
VERTICES = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TRIANGLES = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
RELS = (
    '<?xml version="1.0" encoding="UTF-8"?>\n<Relationships xmlns="http://schemas.openxmlformats.org/'
    'package/2006/relationships"><Relationship Type="http://schemas.microsoft.com/3dmanufacturing/'
    '2013/01/3dmodel" Target="/3D/3dmodel.model" Id="r0"/></Relationships>'
)
MESH = (
    "<mesh><vertices>"
    + "".join(f'<vertex x="{x}" y="{y}" z="{z}"/>' for x, y, z in VERTICES)
    + "</vertices><triangles>"
    + "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in TRIANGLES)
    + "</triangles></mesh>"
)


def transform(rows):
    t = lib3mf.Transform()
    for i in range(4):
        for j in range(3):
            t.Fields[i][j] = float(rows[i][j])
    return t


def tetrahedron(model):
    obj = model.AddMeshObject()
    for v in VERTICES:
        p = lib3mf.Position()
        p.Coordinates[0], p.Coordinates[1], p.Coordinates[2] = v
        obj.AddVertex(p)
    for f in TRIANGLES:
        t = lib3mf.Triangle()
        t.Indices[0], t.Indices[1], t.Indices[2] = f
        obj.AddTriangle(t)
    return obj


def written_by_lib3mf(name, production):
    model = lib3mf.get_wrapper().CreateModel()
    a, b = tetrahedron(model), tetrahedron(model)
    if production:
        part = model.FindOrCreatePackagePart("/3D/Objects/o.model")
        a.SetPackagePart(part)
        b.SetPackagePart(part)
    assembly = model.AddComponentsObject()
    assembly.AddComponent(a, transform([[1, 0, 0], [0, 1, 0], [0, 0, 1], [2, 0, 0]]))
    assembly.AddComponent(b, transform([[0, 1, 0], [-1, 0, 0], [0, 0, 1], [0, 0, 0]]))
    model.AddBuildItem(assembly, transform([[2, 0, 0], [0, 2, 0], [0, 0, 2], [0, 0, 5]]))
    model.QueryWriter("3mf").WriteToFile(str(OUT / name))


def stored(name, model):
    with zipfile.ZipFile(OUT / name, "w", zipfile.ZIP_STORED) as package:
        package.writestr("_rels/.rels", RELS)
        package.writestr("3D/3dmodel.model", model)


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    written_by_lib3mf("components-lib3mf.3mf", production=False)
    written_by_lib3mf("production-lib3mf.3mf", production=True)
    stored(
        "inch-mirror-support.3mf",
        f'<?xml version="1.0" encoding="UTF-8"?>\n<model unit="inch" xmlns="{CORE}" '
        f'xmlns:x="urn:other"><resources><object id="1" type="model">{MESH}</object>'
        f'<object id="2" type="support">{MESH}</object><x:thing><vertex x="9" y="9" z="9"/>'
        "</x:thing></resources><build><item objectid=\"1\"/><item objectid=\"1\" "
        'transform="-1 0 0 0 1 0 0 0 1 -3 0 0"/><item objectid="2"/></build></model>',
    )
    stored(
        "cycle.3mf",
        f'<model xmlns="{CORE}"><resources><object id="1">{MESH}</object>'
        '<object id="2"><components><component objectid="3"/></components></object>'
        '<object id="3"><components><component objectid="2"/></components></object></resources>'
        '<build><item objectid="2"/></build></model>',
    )


if __name__ == "__main__":
    main()
