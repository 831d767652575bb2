"""Synthetic fdem run folders written to the run-folder contract, for tests that need no engine."""
import json
import os
import struct

import numpy as np

ENERGIES = ["E_kin", "E_el", "E_joint", "E_contact", "W_ext", "D_damp", "D_visc", "D_frac", "D_fric", "E_balance"]
BROKEN = ["broken_unit_I", "broken_unit_II", "broken_unit_mixed",
          "broken_interface_I", "broken_interface_II", "broken_interface_mixed"]


def write_vtu(path, X, tri, disp, cell_data, lines=()):
    """VTK XML UnstructuredGrid, appended raw binary, header_type UInt64, like fdem/output.cpp. lines: node pairs of
    line cells after the triangles (cohesive elements); integer cell arrays are written Int32, float ones Float64."""
    lines = np.asarray(lines, np.int64).reshape(-1, 2)
    n_cells = len(tri) + len(lines)
    blob = bytearray()
    xml = ['<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
           'header_type="UInt64">\n<UnstructuredGrid>\n'
           f'<Piece NumberOfPoints="{len(X)}" NumberOfCells="{n_cells}">\n']

    def add(name, arr, vtype, nc):
        data = np.ascontiguousarray(arr).tobytes()
        xml.append(f'<DataArray type="{vtype}" Name="{name}" NumberOfComponents="{nc}" format="appended" '
                   f'offset="{len(blob)}"/>\n')
        blob.extend(struct.pack("<Q", len(data)))
        blob.extend(data)

    xml.append("<PointData>\n")
    add("displacement", np.column_stack((disp, np.zeros(len(X)))).astype("<f8"), "Float64", 3)
    xml.append("</PointData>\n<CellData>\n")
    for name, a in cell_data.items():
        a = np.asarray(a)
        if np.issubdtype(a.dtype, np.floating):
            add(name, a.astype("<f8"), "Float64", 1)
        else:
            add(name, a.astype("<i4"), "Int32", 1)
    xml.append("</CellData>\n<Points>\n")
    add("Points", np.column_stack((X, np.zeros(len(X)))).astype("<f8"), "Float64", 3)
    xml.append("</Points>\n<Cells>\n")
    add("connectivity", np.concatenate((np.asarray(tri, "<i8").ravel(), lines.ravel())).astype("<i8"), "Int64", 1)
    add("offsets", np.concatenate((3 * np.arange(1, len(tri) + 1), 3 * len(tri) + 2 * np.arange(1, len(lines) + 1)))
        .astype("<i8"), "Int64", 1)
    add("types", np.concatenate((np.full(len(tri), 5), np.full(len(lines), 3))).astype("u1"), "UInt8", 1)
    xml.append('</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding="raw">\n   _')
    with open(path, "wb") as f:
        f.write("".join(xml).encode())
        f.write(bytes(blob))
        f.write(b"\n  </AppendedData>\n</VTKFile>\n")


def two_blocks():
    """Two stacked 0.2 x 0.1 m blocks, 4 x 2 squares each split in two triangles, nodes duplicated at the joint."""
    X, tri, unit = [], [], []
    for b, y0 in enumerate((0.0, 0.1)):
        base = len(X)
        for j in range(3):
            for i in range(5):
                X.append((0.05 * i, y0 + 0.05 * j))
        for j in range(2):
            for i in range(4):
                a = base + 5 * j + i
                tri += [(a, a + 1, a + 6), (a, a + 6, a + 5)]
                unit += [b, b]
    return np.array(X, float), np.array(tri), np.array(unit)


def make_run(path, status="completed", fracture=True, n=60, peak=40e3, case="synthetic wall", snapshots=True,
             extra_column=True):
    os.makedirs(path, exist_ok=True)
    t = np.linspace(0, 1.0, n)
    u = 10e-3 * t
    F = peak * (1 - np.exp(-u / 1.5e-3)) * np.exp(-((u / 9e-3) ** 2))
    cols = {"time": t, "step": np.arange(n) * 100, "stage": np.where(t < 0.1, 1, 2), "u_top": u, "F_top": F}
    w = np.concatenate(([0], np.cumsum(0.5 * (F[1:] + F[:-1]) * np.diff(u))))
    cols.update({"E_kin": 1e-3 * w, "E_el": 0.4 * w, "E_joint": 0.05 * w, "E_contact": 0.05 * w, "W_ext": w,
                 "D_damp": 0.1 * w, "D_visc": 0.0 * w, "D_frac": 0.2 * w, "D_fric": 0.199 * w,
                 "E_balance": 1e-3 * np.ones(n)})
    if fracture:
        ramp = np.floor(np.clip((u - 2e-3) / 8e-3, 0, 1) * 12)
        cols.update({"broken_unit_I": ramp // 3, "broken_unit_II": ramp // 4, "broken_unit_mixed": ramp // 6,
                     "broken_interface_I": ramp, "broken_interface_II": ramp // 2, "broken_interface_mixed": ramp // 5})
    if extra_column:
        cols["some_future_column"] = np.ones(n)
    with open(os.path.join(path, "history.csv"), "w") as f:
        f.write(",".join(cols) + "\n")
        for i in range(n):
            f.write(",".join(repr(float(cols[k][i])) for k in cols) + "\n")
    units = {"time": "s", "step": "", "stage": "", "u_top": "m", "F_top": "N"}
    units.update({e: "J" for e in ENERGIES})
    units["E_balance"] = ""
    summary = {"case": case, "case_file": "synthetic.toml", "status": status, "message": "",
               "columns": units, "curve": {"x": "u_top", "y": "F_top"}, "n_triangles": 32, "n_nodes": 30,
               "dt": 1e-6, "steps": int(cols["step"][-1]), "wall_time_s": 1.5, "triangle_steps_per_s": 1e6,
               "threads": 1, "monitors": {"u_top": {"min": 0, "max": float(u.max()), "final": float(u[-1])},
                                          "F_top": {"min": 0, "max": float(F.max()), "final": float(F[-1])}},
               "settings": {}, "reference": {"peak_load_N": peak * 0.7, "source": "made up"}}
    with open(os.path.join(path, "summary.json"), "w") as f:
        json.dump(summary, f)
    if fracture:
        rows = [  # time, control displacement, x, y, class, unit_a, unit_b, mode
            (0.3, 3e-3, 0.075, 0.1, "interface", 0, 1, "I"),
            (0.5, 5e-3, 0.125, 0.1, "interface", 0, 1, "II"),
            (0.6, 6e-3, 0.075, 0.05, "unit", 0, 0, "mixed"),
            (0.7, 7e-3, 0.1, 0.025, "unit", 0, 0, "I"),
            (0.95, 9.5e-3, 0.1, 0.175, "unit", 1, 1, "II"),
        ]
        with open(os.path.join(path, "cracks.csv"), "w") as f:
            f.write("time,control_displacement,x,y,class,unit_a,unit_b,mode\n")
            for r in rows:
                f.write(",".join(map(str, r)) + "\n")
    if snapshots:
        os.makedirs(os.path.join(path, "snapshots"), exist_ok=True)
        X, tri, unit = two_blocks()
        entries = []
        for k, tk in enumerate((0.0, 0.5, 1.0)):
            disp = np.zeros_like(X)
            disp[:, 0] = tk * 2e-3 * (X[:, 1] >= 0.1) + 1e-4 * tk * X[:, 1]
            name = f"snapshots/snap_{k:04d}.vtu"
            write_vtu(os.path.join(path, name), X, tri, disp, {"material": np.zeros(len(tri), int), "region": unit})
            entries.append((tk, name))
        with open(os.path.join(path, "run.pvd"), "w") as f:
            f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n')
            for tk, name in entries:
                f.write(f'    <DataSet timestep="{tk!r}" group="" part="0" file="{name}"/>\n')
            f.write("  </Collection>\n</VTKFile>\n")
    return path
