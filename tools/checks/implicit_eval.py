"""An evaluator of 3MF level sets for the checks, written from the Volumetric and Implicit 1.0
text: it reads the package's XML with ElementTree and the image sheets with png16, and evaluates
the level set's function with numpy. It implements only the node types pgvol writes (an unknown
node fails the check), and nothing of pgvol's code.

- `functionfromimage3d` with filter "linear" and tile style "clamp": voxel centres at
  `(i + 1/2) / n` in UVW, columns along U, rows along V with row 0 at V near 1 (Figure 3-1),
  sheets along W; trilinear between centres, clamped to the outermost centres; the output
  `red` is `pixel / 65535 * valuescale + valueoffset`.
- `implicitfunction`: nodes are evaluated on demand by the references `node.output`, the
  function's input being `inputs.pos`.
"""

from __future__ import annotations

import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from png16 import decode_png16

NS = {
    "c": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02",
    "v": "http://schemas.3mf.io/3dmanufacturing/volumetric/2022/01",
    "i": "http://schemas.3mf.io/3dmanufacturing/implicit/2023/12",
}
I = "{%s}" % NS["i"]
V = "{%s}" % NS["v"]

# Element-wise nodes: numpy does scalars (shape (n,)) and vectors (shape (n, 3)) alike.
UNARY = {"sin": np.sin, "cos": np.cos, "abs": np.abs}
BINARY = {
    "addition": np.add,
    "subtraction": np.subtract,
    "multiplication": np.multiply,
    "division": np.divide,
    "min": np.minimum,
    "max": np.maximum,
}


class Package:
    def __init__(self, path: Path):
        self.zip = zipfile.ZipFile(path)
        self.root = ET.fromstring(self.zip.read("3D/3dmodel.model"))
        resources = self.root.find("c:resources", NS)
        self.resources = {r.get("id"): r for r in resources}
        self.sheets: dict[tuple[str, int], np.ndarray] = {}
        self.evaluated_nodes: set[str] = set()

    def levelset(self) -> ET.Element:
        found = self.root.findall(".//v:levelset", NS)
        assert len(found) == 1, f"{len(found)} level sets"
        return found[0]

    def implicit_function(self) -> ET.Element:
        return self.resources[self.levelset().get("functionid")]

    def levelset_values(self, points: np.ndarray) -> np.ndarray:
        """The level set's channel at object coordinates `points` (n, 3)."""
        ls = self.levelset()
        pos = np.asarray(points, float)
        if ls.get("transform"):
            m = np.array([float(t) for t in ls.get("transform").split()])
            pos = pos @ m[:9].reshape(3, 3) + m[9:]  # [x y z 1] . M, translation last
        out = self.call(ls.get("functionid"), pos)
        return out[ls.get("channel")]

    def call(self, function_id: str, pos: np.ndarray) -> dict:
        element = self.resources[function_id]
        if element.tag == V + "functionfromimage3d":
            return self.image_function(element, pos)
        assert element.tag == I + "implicitfunction", element.tag
        return self.implicit(element, pos)

    # functionfromimage3d

    def sheet(self, image_id: str, k: int) -> np.ndarray:
        key = (image_id, k)
        if key not in self.sheets:
            stack = self.resources[image_id].find("v:imagestack", NS)
            path = stack.findall("v:imagesheet", NS)[k].get("path").lstrip("/")
            self.sheets[key] = decode_png16(self.zip.read(path)).astype(np.float64) / 65535.0
        return self.sheets[key]

    def image_function(self, element: ET.Element, uvw: np.ndarray) -> dict:
        assert element.get("filter", "linear") == "linear"
        assert all(element.get(f"tilestyle{a}") == "clamp" for a in "uvw")
        image_id = element.get("image3did")
        stack = self.resources[image_id].find("v:imagestack", NS)
        cols, rows, sheets = (int(stack.get(k)) for k in ("columncount", "rowcount", "sheetcount"))
        # Continuous pixel coordinates: column along U, row along 1 − V, sheet along W.
        coords = np.stack(
            [uvw[:, 0] * cols - 0.5, (1.0 - uvw[:, 1]) * rows - 0.5, uvw[:, 2] * sheets - 0.5], axis=1
        )
        sizes = np.array([cols, rows, sheets])
        coords = np.clip(coords, 0, sizes - 1)
        lo = np.minimum(np.floor(coords).astype(int), sizes - 1)
        hi = np.minimum(lo + 1, sizes - 1)
        t = coords - lo
        value = np.zeros(len(uvw))
        for corner in range(8):
            pick = [(corner >> a) & 1 for a in range(3)]
            idx = [np.where(pick[a], hi[:, a], lo[:, a]) for a in range(3)]
            weight = np.prod([np.where(pick[a], t[:, a], 1 - t[:, a]) for a in range(3)], axis=0)
            pixel = np.empty(len(uvw))
            for k in np.unique(idx[2]):
                here = idx[2] == k
                pixel[here] = self.sheet(image_id, int(k))[idx[1][here], idx[0][here]]
            value += weight * pixel
        scale = float(element.get("valuescale", 1.0))
        offset = float(element.get("valueoffset", 0.0))
        return {"red": value * scale + offset}

    # implicitfunction

    def implicit(self, element: ET.Element, pos: np.ndarray) -> dict:
        nodes = {}
        for child in element:
            if child.tag in (I + "in", I + "out"):
                continue
            nodes[child.get("identifier")] = child
        inputs = {"pos": pos}
        cache: dict[str, np.ndarray] = {}

        def value(ref: str) -> np.ndarray:
            if ref in cache:
                return cache[ref]
            node_id, output = ref.split(".", 1)
            if node_id == "inputs":
                return inputs[output]
            outputs = self.node(nodes[node_id], value, len(pos))
            for name, v in outputs.items():
                cache[f"{node_id}.{name}"] = v
            return cache[ref]

        result = {}
        for ref in element.find("i:out", NS):
            result[ref.get("identifier")] = value(ref.get("ref"))
        return result

    def node(self, node: ET.Element, value, n: int) -> dict:
        kind = node.tag[len(I):]
        self.evaluated_nodes.add(kind)
        ins = {}
        block = node.find("i:in", NS)
        if block is not None:
            for ref in block:
                ins[ref.get("identifier")] = ref
        arg = {k: (value(r.get("ref")) if not r.tag.endswith("resourceref") else r.get("ref")) for k, r in ins.items()}
        if kind == "constant":
            return {"value": np.full(n, float(node.get("value")))}
        if kind == "constvec":
            v = [float(node.get(a)) for a in "xyz"]
            return {"vector": np.tile(v, (n, 1))}
        if kind == "constresourceid":
            return {"value": node.get("value")}
        if kind in UNARY:
            return {"result": UNARY[kind](arg["A"])}
        if kind in BINARY:
            a, b = arg["A"], arg["B"]
            assert a.shape == b.shape, (kind, a.shape, b.shape)
            with np.errstate(divide="ignore", invalid="ignore"):
                return {"result": BINARY[kind](a, b)}
        if kind == "dot":
            return {"result": np.sum(arg["A"] * arg["B"], axis=1)}
        if kind == "length":
            return {"result": np.linalg.norm(arg["A"], axis=1)}
        if kind == "clamp":
            return {"result": np.maximum(arg["min"], np.minimum(arg["A"], arg["max"]))}
        if kind == "select":
            return {"result": np.where(arg["A"] < arg["B"], arg["C"], arg["D"])}
        if kind == "vectorfromscalar":
            return {"result": np.repeat(arg["A"][:, None], 3, axis=1)}
        if kind == "decomposevector":
            a = arg["A"]
            return {"x": a[:, 0], "y": a[:, 1], "z": a[:, 2]}
        if kind == "composevector":
            return {"result": np.stack([arg["x"], arg["y"], arg["z"]], axis=1)}
        if kind == "functioncall":
            # The called function's id comes from a constresourceid node.
            node_id, out = ins["functionID"].get("ref").split(".")
            function_id = value(f"{node_id}.{out}")
            called = self.call(function_id, arg["pos"])
            return {o.get("identifier"): called[o.get("identifier")] for o in node.find("i:out", NS)}
        raise AssertionError(f"node type {kind} is not one pgvol writes")
