"""lib3mf (the 3MF Consortium's library, PyPI `lib3mf`) as the reader of pgvol's 3MF packages.

lib3mf 2.5.0 reports "Invalid Element in namespace" (error 32934) for every `<v:image3d>` and
`<v:functionfromimage3d>` directly under `<resources>`, also in packages it writes itself: its
resources reader tests `volumedata` with `if` instead of `else if` after those two elements, so
they fall through to the branch for unknown elements. In strict mode that warning is an error.
`reference_package` has lib3mf write the same image stack so that the checks hold pgvol's file to
exactly what lib3mf does with its own, and require a clean strict read once lib3mf's own file
reads strictly.
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass, field
from pathlib import Path

INVALID_ELEMENT = 32934
TEXTURE_REL = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dtexture"
BOX_TRIANGLES = [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                 [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]]


@dataclass
class Read:
    model: object
    warnings: list = field(default_factory=list)
    error: str | None = None


def read(path: Path, strict: bool) -> Read:
    """The package read by lib3mf: the model, the reader's warning codes, the error if it threw."""
    import lib3mf

    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    reader = model.QueryReader("3mf")
    reader.SetStrictModeActive(strict)
    error = None
    try:
        reader.ReadFromFile(str(path))
    except lib3mf.ELib3MFException as e:
        error = str(e)
    warnings = [reader.GetWarning(i)[0] for i in range(reader.GetWarningCount())]
    return Read(model, warnings, error)


def levelsets(model) -> list:
    found, it = [], model.GetLevelSets()
    while it.MoveNext():
        found.append(it.GetCurrentLevelSet())
    return found


def functions(model) -> dict:
    by_id, it = {}, model.GetFunctions()
    while it.MoveNext():
        f = it.GetCurrentFunction()
        by_id[f.GetResourceID()] = f
    return by_id


def reference_package(ours: Path, out: Path, dims) -> Path:
    """lib3mf's own package of the image stack in `ours` (same sheets, `dims` = nx, ny, nz), read
    through a functionfromimage3d by a level set over a box."""
    import lib3mf

    nx, ny, nz = dims
    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    stack = model.AddImageStack(nx, ny, nz)
    with zipfile.ZipFile(ours) as z:
        sheets = sorted(n for n in z.namelist() if n.endswith(".png"))
        assert len(sheets) == nz
        for k, name in enumerate(sheets):
            attachment = model.AddAttachment("/" + name, TEXTURE_REL)
            attachment.ReadFromBuffer(bytearray(z.read(name)))
            stack.SetSheet(k, attachment)
    function = model.AddFunctionFromImage3D(stack)
    box = model.AddMeshObject()
    for k in range(8):
        p = lib3mf.Position()
        for a in range(3):
            p.Coordinates[a] = float((k >> a) & 1)
        box.AddVertex(p)
    for t in BOX_TRIANGLES:
        tri = lib3mf.Triangle()
        for a in range(3):
            tri.Indices[a] = t[a]
        box.AddTriangle(tri)
    level = model.AddLevelSet()
    level.SetFunction(function)
    level.SetChannelName("red")
    level.SetMesh(box)
    level.SetMeshBBoxOnly(True)
    model.AddBuildItem(level, wrapper.GetIdentityTransform())
    model.QueryWriter("3mf").WriteToFile(str(out))
    return out


def check_reads_as_lib3mf_own(ours: Path, reference: Path) -> Read:
    """Reads `ours` strictly if lib3mf reads its own `reference` strictly, else requires the same
    strict failure and, read leniently, exactly the reference's warnings (the known defect
    above, nothing of pgvol's). Returns the lenient (or strict) read of `ours`."""
    ref_strict = read(reference, strict=True)
    ours_strict = read(ours, strict=True)
    if ref_strict.error is None:
        assert ours_strict.error is None and ours_strict.warnings == [], (ours_strict.error, ours_strict.warnings)
        return ours_strict
    assert ours_strict.error == ref_strict.error, (ours_strict.error, ref_strict.error)
    ref_lenient = read(reference, strict=False)
    assert ref_lenient.error is None and set(ref_lenient.warnings) <= {INVALID_ELEMENT}, ref_lenient.warnings
    ours_lenient = read(ours, strict=False)
    assert ours_lenient.error is None, ours_lenient.error
    assert ours_lenient.warnings == ref_lenient.warnings, (ours_lenient.warnings, ref_lenient.warnings)
    return ours_lenient
