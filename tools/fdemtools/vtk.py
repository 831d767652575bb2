"""Minimal readers for fdem's VTK files: run.pvd (snapshot list) and *.vtu (UnstructuredGrid with appended raw
binary data, or inline ascii), enough for crack maps. Not a general VTK reader: no compression, no base64."""
from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET

import numpy as np

from .common import ToolError

_TYPES = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4", "Int16": "<i2", "Int8": "i1",
          "UInt64": "<u8", "UInt32": "<u4", "UInt16": "<u2", "UInt8": "u1"}


def read_pvd(path: str) -> list:
    """[(time s, absolute path of the .vtu)] in file order."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ToolError(f"{path}: unreadable PVD file ({e})") from None
    base = os.path.dirname(path)
    out = []
    for ds in root.iter("DataSet"):
        try:
            out.append((float(ds.get("timestep", "nan")), os.path.join(base, ds.get("file", ""))))
        except ValueError:
            raise ToolError(f"{path}: bad timestep '{ds.get('timestep')}'") from None
    return out


def read_vtu(path: str) -> dict:
    """{'points': (n,3), 'cells': list of (connectivity arrays), 'types': (m,), 'point_data': {name: array},
    'cell_data': {name: array}}; arrays with several components have shape (n, components)."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise ToolError(f"{path}: cannot read ({e.strerror})") from None
    blob = b""
    m = re.search(rb"<AppendedData[^>]*>\s*_", raw)
    if m:
        blob = raw[m.end():]
        end = raw.rfind(b"</AppendedData>")
        xml = raw[:m.start()] + b"</VTKFile>" if end < 0 else raw[:m.start()] + raw[end + len(b"</AppendedData>"):]
    else:
        xml = raw
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as e:
        raise ToolError(f"{path}: not a readable VTU file ({e})") from None
    if root.get("compressor"):
        raise ToolError(f"{path}: compressed VTU files are not supported")
    header = "<u8" if root.get("header_type", "UInt32") == "UInt64" else "<u4"
    hsize = np.dtype(header).itemsize

    def array(el):
        t = el.get("type")
        if t not in _TYPES:
            raise ToolError(f"{path}: unsupported data type '{t}'")
        dt = np.dtype(_TYPES[t])
        fmt = el.get("format", "ascii")
        if fmt == "appended":
            off = int(el.get("offset", "0"))
            if off + hsize > len(blob):
                raise ToolError(f"{path}: truncated appended data")
            nbytes = int(np.frombuffer(blob, dtype=header, count=1, offset=off)[0])
            if off + hsize + nbytes > len(blob):
                raise ToolError(f"{path}: truncated appended data")
            a = np.frombuffer(blob, dtype=dt, count=nbytes // dt.itemsize, offset=off + hsize).copy()
        elif fmt == "ascii":
            a = np.array((el.text or "").split(), dtype=dt)
        else:
            raise ToolError(f"{path}: data format '{fmt}' is not supported")
        nc = int(el.get("NumberOfComponents", "1"))
        return a.reshape(-1, nc) if nc > 1 else a

    piece = root.find(".//Piece")
    if piece is None:
        raise ToolError(f"{path}: no Piece in the VTU file")
    pts_el = piece.find("Points/DataArray")
    if pts_el is None:
        raise ToolError(f"{path}: no Points in the VTU file")
    out = {"points": array(pts_el), "point_data": {}, "cell_data": {}}
    cells = {el.get("Name"): el for el in piece.findall("Cells/DataArray")}
    for k in ("connectivity", "offsets", "types"):
        if k not in cells:
            raise ToolError(f"{path}: no '{k}' in Cells")
    out["connectivity"] = array(cells["connectivity"]).astype(np.int64)
    out["offsets"] = array(cells["offsets"]).astype(np.int64)
    out["types"] = array(cells["types"]).astype(np.int64)
    for el in piece.findall("PointData/DataArray"):
        out["point_data"][el.get("Name")] = array(el)
    for el in piece.findall("CellData/DataArray"):
        out["cell_data"][el.get("Name")] = array(el)
    return out


def triangles(vtu: dict):
    """(indices of the triangle cells among all cells, (k,3) node indices of the triangles)."""
    offs = vtu["offsets"]
    starts = np.concatenate(([0], offs[:-1]))
    sel = np.nonzero((vtu["types"] == 5) & (offs - starts == 3))[0]
    conn = vtu["connectivity"]
    tri = np.stack([conn[starts[sel] + i] for i in range(3)], axis=1) if len(sel) else np.zeros((0, 3), np.int64)
    return sel, tri
