#!/usr/bin/env python3
"""Converts one shared particle frame into every particle format Meniscus reads (tests/data/formats/).

The source is the SPlisHSPlasH double dam break frame 26 (4732 particles, id and velocity) from
../shared/data/splashsurf/, a big-endian binary legacy VTK file. Every output carries the same positions, ids and
velocities, so the reader tests (tests/native/test_io_*.cpp) can compare each reader with the VTK reader value for value (text
formats print the shortest decimal that reads back as the same float32).

Besides the full frame it writes variants/: the first 5 particles in every VTK XML encoding combination (ascii,
inline base64, appended raw, appended base64; zlib or not; UInt32 or UInt64 headers; both byte orders) and in the
other formats (legacy binary VTK, BGEO, PLY in all three encodings, raw .xyz, .npy, deflated .npz) and their rarer
variants (float64 Fortran-order, big-endian and float16 .npy, .npz with separate x, y, z members, text .xyz,
semicolon CSV) and as Houdini JSON geometry (ASCII .geo with tuples or arrays, binary .bgeo in both byte orders with
paged values, packing and a constant page). The bad-input tests cut and damage these small files.

Only numpy and the standard library are used. Run from anywhere:  python3 tests/data/formats/make_samples.py
The outputs are committed; rerunning gives identical bytes.
"""
import base64
import gzip
import io
import pathlib
import struct
import zipfile
import zlib

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
SHARED = HERE.parents[2].parent / "shared" / "data" / "splashsurf"
SOURCE = SHARED / "double_dam_break_frame_26_4732_particles.vtk"


# ---- reading the source frame ------------------------------------------------------------------------------------

def read_legacy_vtk(path):
    """Positions, ids and velocities of the SPlisHSPlasH binary VTK layout (POINTS, SCALARS id, FIELD velocity)."""
    data = path.read_bytes()

    def after(marker, start=0):
        at = data.index(marker, start)
        return data.index(b"\n", at) + 1

    n = int(data[data.index(b"POINTS ") + 7:].split(b" ", 1)[0])
    p = after(b"POINTS ")
    positions = np.frombuffer(data, ">f4", 3 * n, p).reshape(n, 3).astype("<f4")
    p = after(b"LOOKUP_TABLE", data.index(b"SCALARS id"))
    ids = np.frombuffer(data, ">u4", n, p).astype("<u4")
    p = after(b"velocity 3 ")
    velocity = np.frombuffer(data, ">f4", 3 * n, p).reshape(n, 3).astype("<f4")
    return positions, ids, velocity


def text(value):
    """Shortest decimal that reads back as the same float32 (numpy's repr algorithm)."""
    return str(np.float32(value)) if np.issubdtype(np.asarray(value).dtype, np.floating) else str(int(value))


def text_rows(*columns):
    """Rows of text, one per particle, from (N,) or (N,k) arrays."""
    parts = []
    for column in columns:
        column = np.asarray(column)
        if column.ndim == 1:
            column = column[:, None]
        parts.append([[text(v) for v in row] for row in column])
    return [sum((p[i] for p in parts), []) for i in range(len(parts[0]))]


# ---- VTK XML -----------------------------------------------------------------------------------------------------

VTK_TYPES = {"f4": "Float32", "f8": "Float64", "u4": "UInt32", "i4": "Int32", "i8": "Int64", "u1": "UInt8"}


class VtkXml:
    """Writes VTK XML files the way vtkXMLWriter does: header word(s) before every binary array, the zlib header
    base64-encoded on its own, appended offsets counted from the '_'."""

    def __init__(self, mode, compressed=False, header="UInt32", order="<", block_size=32768):
        self.mode, self.compressed, self.header, self.order, self.block_size = mode, compressed, header, order, block_size
        self.appended = bytearray()

    def _word(self, values):
        return np.asarray(values, self.order + ("u4" if self.header == "UInt32" else "u8")).tobytes()

    def _payload(self, raw):
        """(header bytes, data bytes) of one array."""
        if not self.compressed:
            return self._word([len(raw)]), raw
        blocks = [raw[i:i + self.block_size] for i in range(0, len(raw), self.block_size)]
        packed = [zlib.compress(b, 6) for b in blocks]
        last = len(blocks[-1]) if blocks and len(blocks[-1]) != self.block_size else 0
        header = self._word([len(blocks), self.block_size, last] + [len(p) for p in packed])
        return header, b"".join(packed)

    def array(self, name, values, components, indent="        "):
        values = np.ascontiguousarray(values)
        kind = values.dtype.str[1:]
        attrs = f'type="{VTK_TYPES[kind]}"' + (f' Name="{name}"' if name else "") + f' NumberOfComponents="{components}"'
        if self.mode == "ascii":
            body = "\n".join(" ".join(row) for row in text_rows(values)) if len(values) else ""
            return f'{indent}<DataArray {attrs} format="ascii">\n{body}\n{indent}</DataArray>\n'
        header, data = self._payload(values.astype(self.order + kind).tobytes())
        if self.mode == "binary":
            encoded = (base64.b64encode(header) + base64.b64encode(data)) if self.compressed else base64.b64encode(header + data)
            return f'{indent}<DataArray {attrs} format="binary">\n{encoded.decode()}\n{indent}</DataArray>\n'
        offset = len(self.appended)
        if self.mode == "raw":
            self.appended += header + data
        else:  # appended base64
            self.appended += (base64.b64encode(header) + base64.b64encode(data)) if self.compressed else base64.b64encode(header + data)
        return f'{indent}<DataArray {attrs} format="appended" offset="{offset}"/>\n'

    def file(self, positions, attributes, dataset="UnstructuredGrid", cells=True):
        n = len(positions)
        out = ['<?xml version="1.0"?>\n<!-- written by tests/data/formats/make_samples.py -->\n']
        root = f'<VTKFile type="{dataset}" version="1.0" byte_order="{"LittleEndian" if self.order == "<" else "BigEndian"}"'
        root += f' header_type="{self.header}"' + (' compressor="vtkZLibDataCompressor"' if self.compressed else "") + ">\n"
        out.append(root)
        out.append(f"  <{dataset}>\n")
        if dataset == "UnstructuredGrid":
            out.append(f'    <Piece NumberOfPoints="{n}" NumberOfCells="{n if cells else 0}">\n')
        else:
            out.append(f'    <Piece NumberOfPoints="{n}" NumberOfVerts="{n if cells else 0}" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="0">\n')
        out.append('      <PointData Scalars="id" Vectors="velocity">\n')
        for name, values, components in attributes:
            out.append(self.array(name, values, components))
        out.append("      </PointData>\n      <CellData>\n      </CellData>\n      <Points>\n")
        out.append(self.array("Points", positions, 3))
        out.append("      </Points>\n")
        section = "Cells" if dataset == "UnstructuredGrid" else "Verts"
        count = n if cells else 0
        out.append(f"      <{section}>\n")
        out.append(self.array("connectivity", np.arange(count, dtype="<i8"), 1))
        out.append(self.array("offsets", np.arange(1, count + 1, dtype="<i8"), 1))
        if dataset == "UnstructuredGrid":
            out.append(self.array("types", np.ones(count, dtype="u1"), 1))
        out.append(f"      </{section}>\n    </Piece>\n  </{dataset}>\n")
        data = "".join(out).encode()
        if self.mode in ("raw", "base64"):
            encoding = "raw" if self.mode == "raw" else "base64"
            data += f'  <AppendedData encoding="{encoding}">\n   _'.encode() + bytes(self.appended) + b"\n  </AppendedData>\n"
        return data + b"</VTKFile>\n"


# ---- other formats ---------------------------------------------------------------------------------------------

def ply(positions, ids, velocity, fmt):
    n = len(positions)
    names = "<" if fmt == "binary_little_endian" else ">"
    header = (f"ply\nformat {fmt} 1.0\ncomment written by tests/data/formats/make_samples.py\nelement vertex {n}\n"
              "property float x\nproperty float y\nproperty float z\nproperty uint id\n"
              "property float vx\nproperty float vy\nproperty float vz\nelement face 0\n"
              "property list uchar int vertex_indices\nend_header\n").encode()
    if fmt == "ascii":
        return header + "".join(" ".join(r) + "\n" for r in text_rows(positions, ids, velocity)).encode()
    record = np.dtype([("p", names + "f4", (3,)), ("id", names + "u4"), ("v", names + "f4", (3,))])
    table = np.empty(n, record)
    table["p"], table["id"], table["v"] = positions, ids, velocity
    return header + table.tobytes()


def bgeo(positions, ids, velocity):
    """Classic Houdini BGEO v5 as Partio writes it: big-endian header, attribute definitions, then per point
    x y z w and the attribute words; the trailing 0x00 0xff close the (empty) extra section."""
    n = len(positions)
    out = [b"BgeoV", struct.pack(">i", 5), struct.pack(">8i", n, 0, 0, 0, 2, 0, 0, 0)]
    out.append(struct.pack(">H", 2) + b"id" + struct.pack(">Hi", 1, 1) + struct.pack(">i", 0))
    out.append(struct.pack(">H", 8) + b"velocity" + struct.pack(">Hi", 3, 5) + struct.pack(">3f", 0, 0, 0))
    record = np.dtype([("p", ">f4", (4,)), ("id", ">i4"), ("v", ">f4", (3,))])
    table = np.zeros(n, record)
    table["p"][:, :3], table["p"][:, 3], table["id"], table["v"] = positions, 1.0, ids, velocity
    return b"".join(out) + table.tobytes() + b"\x00\xff"


def legacy_vtk_binary(positions, ids, velocity):
    """The SPlisHSPlasH layout: POINTS, one VERTEX cell each, SCALARS id, FIELD velocity, big-endian."""
    n = len(positions)
    cells = np.stack([np.ones(n, ">i4"), np.arange(n, dtype=">i4")], 1)
    return b"".join([
        b"# vtk DataFile Version 4.1\nSPlisHSPlasH particle data\nBINARY\nDATASET UNSTRUCTURED_GRID\n",
        f"POINTS {n} float\n".encode(), positions.astype(">f4").tobytes(), b"\n",
        f"CELLS {n} {2 * n}\n".encode(), cells.tobytes(), b"\n",
        f"CELL_TYPES {n}\n".encode(), np.ones(n, ">i4").tobytes(), b"\n",
        f"POINT_DATA {n}\nSCALARS id unsigned_int 1\nLOOKUP_TABLE id_table\n".encode(), ids.astype(">u4").tobytes(), b"\n",
        f"FIELD FieldData 1\nvelocity 3 {n} float\n".encode(), velocity.astype(">f4").tobytes(), b"\n"])


# ---- Houdini JSON geometry ----------------------------------------------------------------------------------------

class Uniform:
    """A numeric run written as one binary-JSON uniform array (a plain list in ASCII JSON)."""

    def __init__(self, values, dtype):
        self.values, self.dtype = np.asarray(values), dtype


def _length(n, order):
    if n < 0xf1:
        return bytes([n])
    if n < 1 << 16:
        return b"\xf2" + struct.pack(order + "H", n)
    if n < 1 << 32:
        return b"\xf4" + struct.pack(order + "I", n)
    return b"\xf8" + struct.pack(order + "Q", n)


class BinaryJson:
    """SideFX binary JSON (UT_JSONDefines.h): 0x7f and the magic 0x624a534e in the file's byte order, one byte per
    token, encoded lengths; repeated strings become token definitions (0x2b) and references (0x26)."""

    UNIFORM = {"f4": 0x19, "f8": 0x1a, "i4": 0x13, "i8": 0x14, "u1": 0x21, "i2": 0x12}

    def __init__(self, order="<"):
        self.order, self.tokens = order, {}

    def encode(self, value):
        return b"\x7f" + struct.pack(self.order + "I", 0x624A534E) + self._value(value)

    def _string(self, text):
        data = text.encode()
        if text in self.tokens:
            return b"\x26" + _length(self.tokens[text], self.order)
        if len(self.tokens) < 200 and len(data) > 1:  # define once, refer afterwards
            self.tokens[text] = len(self.tokens)
            return (b"\x2b" + _length(self.tokens[text], self.order) + _length(len(data), self.order) + data +
                    b"\x26" + _length(self.tokens[text], self.order))
        return b"\x27" + _length(len(data), self.order) + data

    def _value(self, v):
        o = self.order
        if v is None:
            return b"\x00"
        if v is True or v is False:
            return b"\x31" if v else b"\x30"
        if isinstance(v, int):
            return b"\x13" + struct.pack(o + "i", v)
        if isinstance(v, float):
            return b"\x1a" + struct.pack(o + "d", v)
        if isinstance(v, str):
            return self._string(v)
        if isinstance(v, Uniform):
            if v.dtype == "bool":
                bits = np.zeros((len(v.values) + 31) // 32, o + "u4")
                for i, flag in enumerate(v.values):
                    bits[i // 32] |= np.uint32(bool(flag)) << np.uint32(i % 32)
                return b"\x40\x10" + _length(len(v.values), o) + bits.tobytes()
            return (b"\x40" + bytes([self.UNIFORM[v.dtype]]) + _length(len(v.values), o) +
                    v.values.astype(o + v.dtype).tobytes())
        if isinstance(v, dict):
            return b"\x7b" + b"".join(self._string(k) + self._value(x) for k, x in v.items()) + b"\x7d"
        return b"\x5b" + b"".join(self._value(x) for x in v) + b"\x5d"


def ascii_json(v):
    if isinstance(v, Uniform):
        return ascii_json([bool(x) if v.dtype == "bool" else (int(x) if v.dtype[0] in "iu" else float(x)) for x in v.values])
    if isinstance(v, float):
        return repr(float(np.float32(v))) if v == v else "NaN"
    if isinstance(v, dict):
        return "{" + ",".join(f'"{k}":{ascii_json(x)}' for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ",".join(ascii_json(x) for x in v) + "]"
    if v is True or v is False:
        return "true" if v else "false"
    if v is None:
        return "null"
    return f'"{v}"' if isinstance(v, str) else str(v)


def paged(values, page, packing, constant=None):
    """rawpagedata: per page, per packing group, the group's components element by element; a page flagged constant
    for a group stores that group's first tuple only. Returns (flat values, constantpageflags or None)."""
    values = np.asarray(values).reshape(len(values), -1)
    flat, flags = [], [[] for _ in packing]
    for start in range(0, len(values), page):
        rows = values[start:start + page]
        column = 0
        for g, size in enumerate(packing):
            block = rows[:, column:column + size]
            is_constant = constant is not None and constant(start // page, g) and (block == block[0]).all()
            flags[g].append(is_constant)
            flat.extend((block[:1] if is_constant else block).ravel())
            column += size
    return flat, (flags if constant is not None else None)


def houdini_attribute(name, values, storage, layout, page=1024, packing=None, constant=None, dtype="f4"):
    values = np.asarray(values)
    size = 1 if values.ndim == 1 else values.shape[1]
    body = ["size", size, "storage", storage]
    if layout == "tuples":
        body += ["tuples", [Uniform(row, dtype) for row in values.reshape(len(values), -1)] if size > 1 else Uniform(values, dtype)]
    elif layout == "arrays":
        body += ["arrays", [Uniform(values.reshape(len(values), -1)[:, k], dtype) for k in range(size)]]
    else:
        packing = packing or [size]
        flat, flags = paged(values, page, packing, constant)
        body += ["pagesize", page, "packing", packing]
        if flags is not None:
            body += ["constantpageflags", [Uniform(f, "bool") for f in flags]]
        body += ["rawpagedata", Uniform(flat, dtype)]
    definition = ["scope", "public", "type", "numeric", "name", name, "options", {}]
    return [definition, ["size", size, "storage", storage, "defaults", ["size", 1, "storage", "fpreal64", "values", [0.0]],
                         "values", body]]


def houdini_geometry(positions, ids, velocity, layout, page=1024, p_packing=None, v_constant=None):
    n = len(positions)
    names = ["water"] * n
    return [
        "fileversion", "19.5.303", "hasindex", False, "pointcount", n, "vertexcount", n, "primitivecount", 1,
        "info", {"software": "make_samples.py", "bounds": [0.0, 1.0, 0.0, 1.0, 0.0, 1.0]},
        "topology", ["pointref", ["indices", Uniform(np.arange(n), "i4")]],
        "attributes", [
            "vertexattributes", [],
            "pointattributes", [
                houdini_attribute("P", positions, "fpreal32", layout, page, p_packing),
                houdini_attribute("id", ids, "int32", layout, page, dtype="i4"),
                houdini_attribute("v", velocity, "fpreal32", layout, page, constant=v_constant),
                [["scope", "public", "type", "string", "name", "name", "options", {}],
                 ["size", 1, "storage", "int32", "strings", ["water"], "indices",
                  ["size", 1, "storage", "int32", "arrays", [Uniform(np.zeros(n), "i4")]]]],
            ],
            "globalattributes", [],
        ],
        "primitives", [[["type", "Part"], ["vertex", Uniform(np.arange(n), "i4"), "renderproperties", {"type": "sphere"}]]],
    ] if names else None


def npy_bytes(array):
    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()


def npz_bytes(members, compressed):
    # np.savez stamps the current time into the zip; a fixed date keeps the committed files reproducible.
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED if compressed else zipfile.ZIP_STORED) as z:
        for name, array in members.items():
            info = zipfile.ZipInfo(name + ".npy", date_time=(2026, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED if compressed else zipfile.ZIP_STORED
            with z.open(info, "w", force_zip64=True) as f:  # numpy forces zip64 too
                f.write(npy_bytes(array))
    return buffer.getvalue()


def csv(positions, ids, velocity):
    # ParaView's "Save Data" CSV layout: attributes first, then Points:0..2, every name quoted.
    header = '"id","velocity:0","velocity:1","velocity:2","Points:0","Points:1","Points:2"\n'
    return (header + "".join(",".join(r) + "\n" for r in text_rows(ids, velocity, positions))).encode()


def main():
    positions, ids, velocity = read_legacy_vtk(SOURCE)
    n = len(positions)
    assert n == 4732
    attributes = [("id", ids, 1), ("velocity", velocity, 3)]
    files = {
        "dam26_ascii.vtu": VtkXml("ascii").file(positions, attributes, cells=False),
        "dam26_base64_be.vtp": VtkXml("binary", True, "UInt64", ">").file(positions, attributes, "PolyData", cells=False),
        # Houdini 19 binary JSON geometry as Houdini saves .bgeo.gz: paged values (1024 per page), gzip-compressed.
        "dam26_houdini.bgeo.gz": gzip.compress(BinaryJson().encode(houdini_geometry(positions, ids, velocity, "paged")), mtime=0),
        "dam26_appended_raw.vtu": VtkXml("raw").file(positions, attributes),
        "dam26_zlib_base64.vtu": VtkXml("base64", compressed=True, block_size=16384).file(positions, attributes),
        "dam26_binary.ply": ply(positions, ids, velocity, "binary_little_endian"),
        "dam26.xyz": positions.astype("<f4").tobytes(),
        "dam26.npy": npy_bytes(positions),
        "dam26.npz": npz_bytes({"positions": positions, "id": ids, "velocity": velocity}, False),
        "dam26_compressed.npz": npz_bytes({"positions": positions, "id": ids, "velocity": velocity}, True),
        "dam26.csv": csv(positions, ids, velocity),
    }

    # Tiny files for every VTK XML encoding (the first 5 particles).
    small = [positions[:5], [("id", ids[:5], 1), ("velocity", velocity[:5], 3)]]
    variants = {"ascii.vtu": VtkXml("ascii").file(*small)}
    for mode in ("binary", "raw", "base64"):
        for compressed in (False, True):
            for header in ("UInt32", "UInt64"):
                for order in ("<", ">"):
                    name = f"{mode}_{'zlib' if compressed else 'plain'}_{header.lower()}_{'le' if order == '<' else 'be'}.vtu"
                    # A 16-byte block size splits even 5 particles into many zlib blocks.
                    writer = VtkXml(mode, compressed, header, order, block_size=16)
                    variants[name] = writer.file(*small)
    variants["polydata_raw.vtp"] = VtkXml("raw").file(*small, dataset="PolyData")
    # Other formats' variants, same 5 particles.
    p5, i5, v5 = positions[:5], ids[:5], velocity[:5]
    variants["binary.bgeo"] = bgeo(p5, i5, v5)
    variants["binary.vtk"] = legacy_vtk_binary(p5, i5, v5)
    variants["binary_le.ply"] = ply(p5, i5, v5, "binary_little_endian")
    variants["positions.npy"] = npy_bytes(p5)
    variants["raw.xyz"] = p5.astype("<f4").tobytes()
    variants["deflated.npz"] = npz_bytes({"positions": p5, "id": i5, "velocity": v5}, True)
    variants["ascii.ply"] = ply(p5, i5, v5, "ascii")
    # Houdini JSON geometry: ASCII with tuples and with arrays; binary in both byte orders, 2-element pages with P
    # packed as [1, 2]; the big-endian one with velocity's page 1 (particles 2 and 3) stored as a constant page.
    variants["houdini_tuples.geo"] = ascii_json(houdini_geometry(p5, i5, v5, "tuples")).encode()
    variants["houdini_arrays.geo"] = ascii_json(houdini_geometry(p5, i5, v5, "arrays")).encode()
    variants["houdini_paged_le.bgeo"] = BinaryJson("<").encode(houdini_geometry(p5, i5, v5, "paged", 2, [1, 2]))
    v_constant = v5.copy()
    v_constant[3] = v_constant[2]
    variants["houdini_constant_be.bgeo"] = BinaryJson(">").encode(
        houdini_geometry(p5, i5, v_constant, "paged", 2, None, lambda page, group: page == 1))
    variants["binary_be.ply"] = ply(p5, i5, v5, "binary_big_endian")
    record = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("id", "<u4"), ("velocity", "<f4", (3,))])
    table = np.empty(5, record)
    table["x"], table["y"], table["z"] = p5.T
    table["id"], table["velocity"] = i5, v5
    variants["structured.npy"] = npy_bytes(table)
    variants["f8_fortran.npy"] = npy_bytes(np.asfortranarray(p5.astype("<f8")))
    variants["f4_big_endian.npy"] = npy_bytes(p5.astype(">f4"))
    variants["f2.npy"] = npy_bytes(p5.astype("<f2"))
    variants["xyz_members.npz"] = npz_bytes({"x": p5[:, 0], "y": p5[:, 1], "z": p5[:, 2], "id": i5, "time": np.float64(0.5)}, True)
    variants["text.xyz"] = "".join(" ".join(r) + "\n" for r in text_rows(p5)).encode()
    variants["semicolon.csv"] = ("# exported by a spreadsheet\nX;Y;Z;density\n" +
                                 "".join(";".join(r) + "\n" for r in text_rows(p5, np.full(5, 1000.5, "<f4")))).encode()

    (HERE / "variants").mkdir(exist_ok=True)
    for name, data in files.items():
        (HERE / name).write_bytes(data)
    for name, data in variants.items():
        (HERE / "variants" / name).write_bytes(data)
    total = sum(len(d) for d in files.values()) + sum(len(d) for d in variants.values())
    print(f"wrote {len(files)} frames and {len(variants)} variants, {total / 1e6:.2f} MB")


if __name__ == "__main__":
    main()
