#!/usr/bin/env python3
"""Builds the committed seed corpus fuzz/corpus/<harness>/ from the shared frames and the test samples.

Seeds are small on purpose (mutations on a few KiB reach far more code per second than on 200 KiB): the shared
frames are cut down to their first particles with every section and attribute kept, in each format the harness
reads. Rerunning gives identical files. Run:  python3 fuzz/make_corpus.py
"""
import gzip
import pathlib
import shutil
import struct
import sys

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
SHARED = ROOT.parent / "shared" / "data"
sys.path.insert(0, str(ROOT / "tests" / "data" / "formats"))
import make_samples as samples  # noqa: E402  (the converters of the test samples)

CORPUS = HERE / "corpus"


def legacy_vtk(positions, ids, velocity, binary=True):
    """The SPlisHSPlasH layout: POINTS, one VERTEX cell each, SCALARS id, FIELD velocity."""
    n = len(positions)
    out = [b"# vtk DataFile Version 4.1\nSPlisHSPlasH particle data\n", b"BINARY\n" if binary else b"ASCII\n",
           b"DATASET UNSTRUCTURED_GRID\n", f"POINTS {n} float\n".encode()]

    def block(array, dtype):
        if binary:
            return np.asarray(array).astype(dtype).tobytes() + b"\n"
        return (" ".join(samples.text(v) for v in np.asarray(array).ravel()) + "\n").encode()

    out.append(block(positions, ">f4"))
    out.append(f"CELLS {n} {2 * n}\n".encode())
    out.append(block(np.stack([np.ones(n, int), np.arange(n)], 1), ">i4"))
    out.append(f"CELL_TYPES {n}\n".encode())
    out.append(block(np.ones(n, int), ">i4"))
    out.append(f"POINT_DATA {n}\nSCALARS id unsigned_int 1\nLOOKUP_TABLE id_table\n".encode())
    out.append(block(ids, ">u4"))
    out.append(f"FIELD FieldData 1\nvelocity 3 {n} float\n".encode())
    out.append(block(velocity, ">f4"))
    return b"".join(out)


def reduced_bgeo(path, count):
    """The first `count` points of a shared BGEO frame, header and attribute definitions as they are."""
    data = gzip.decompress(path.read_bytes())
    n_points, = struct.unpack(">i", data[9:13])
    n_attributes, = struct.unpack(">i", data[25:29])
    pos = 41
    words = 4
    for _ in range(n_attributes):
        name_length, = struct.unpack(">H", data[pos:pos + 2])
        pos += 2 + name_length
        size, kind = struct.unpack(">Hi", data[pos:pos + 6])
        pos += 6 + 4 * size  # float/int/vector defaults (the shared files have no index attributes)
        words += size
    header = bytearray(data[:pos])
    header[9:13] = struct.pack(">i", count)
    return bytes(header) + data[pos:pos + 4 * words * count] + data[pos + 4 * words * n_points:]


def mantaflow_uni(magic, count, element_bytes, payload, grid=(16, 16, 8)):
    """A Mantaflow UNI particle file (PB02 system or PD01 data): the 292-byte header, then the elements."""
    header = magic + struct.pack("<6i", count, *grid, 0 if element_bytes == 16 else 1, element_bytes)
    return header + b"mantaflow seed".ljust(256, b"\0") + bytes(8) + payload


def mantaflow_config(resolution=(16, 16, 8)):
    """config_####.uni as Blender writes it (204 bytes): a 2 x 2 x 1 m domain turned about z, moved to (3, 4, 5)."""
    return (struct.pack("<4i", 16, *resolution) + struct.pack("<2f", 1 / 16, 0.104) +
            struct.pack("<9f", -1, -1, -1, 1, 1, 1, -1, -1, -1) + struct.pack("<3i", 0, 0, 0) + struct.pack("<3f", 0, 0, 0) +
            struct.pack("<16f", 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 0.5, 0, 3, 4, 5, 1) + struct.pack("<9i", 16, 16, 8, 0, 0, 0, 16, 16, 8) +
            struct.pack("<3f", 0, 0, 0) + struct.pack("<f", 1.0) + b"C01\0")


def write(harness, name, data):
    folder = CORPUS / harness
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(data)


def main():
    if CORPUS.exists():
        shutil.rmtree(CORPUS)
    positions, ids, velocity = samples.read_legacy_vtk(samples.SOURCE)
    n = 12
    p, i, v = positions[:n], ids[:n], velocity[:n]
    attributes = [("id", i, 1), ("velocity", v, 3)]
    io_data = ROOT / "tests" / "data" / "io"
    variants = ROOT / "tests" / "data" / "formats" / "variants"

    # Legacy VTK: the shared layout, binary and ASCII, and the hand-written test files.
    write("vtk", "splishsplash_binary.vtk", legacy_vtk(p, i, v))
    write("vtk", "splishsplash_ascii.vtk", legacy_vtk(p, i, v, binary=False))
    for f in sorted(io_data.glob("*.vtk")):
        write("vtk", f.name, f.read_bytes())

    # BGEO: reduced shared frames (plain: the harness sees no gzip).
    write("bgeo", "dam_break.bgeo", reduced_bgeo(SHARED / "splashsurf" / "dam_break_frame_9_6859_particles.bgeo", n))
    write("bgeo", "fluid_50.bgeo", reduced_bgeo(SHARED / "splashsurf" / "ParticleData_Fluid_50.bgeo", n))
    write("bgeo", "hilbert.bgeo", reduced_bgeo(SHARED / "splashsurf" / "hilbert_46843_particles.bgeo", n))

    # VTK XML: every encoding variant, plus a multi-piece file.
    for f in sorted(variants.glob("*.vt[up]")):
        write("vtu", f.name, f.read_bytes())

    # PLY, NumPy, CSV, XYZ.
    write("ply", "binary_le.ply", samples.ply(p, i, v, "binary_little_endian"))
    write("ply", "binary_be.ply", samples.ply(p, i, v, "binary_big_endian"))
    write("ply", "ascii.ply", samples.ply(p, i, v, "ascii"))
    write("ply", "quad_ascii.ply", (io_data / "quad_ascii.ply").read_bytes())
    write("npy", "positions.npy", samples.npy_bytes(p))
    write("npy", "f8_fortran.npy", samples.npy_bytes(np.asfortranarray(p.astype("<f8"))))
    write("npy", "f2.npy", samples.npy_bytes(p.astype("<f2")))
    record = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("id", "<u4"), ("velocity", ">f4", (3,))])
    table = np.empty(n, record)
    table["x"], table["y"], table["z"] = p.T
    table["id"], table["velocity"] = i, v
    write("npy", "structured.npy", samples.npy_bytes(table))
    members = {"positions": p, "id": i, "velocity": v}
    write("npz", "stored.npz", samples.npz_bytes(members, False))
    write("npz", "deflated.npz", samples.npz_bytes(members, True))
    write("npz", "xyz_members.npz", (variants / "xyz_members.npz").read_bytes())
    write("csv", "paraview.csv", samples.csv(p, i, v))
    write("csv", "semicolon.csv", (variants / "semicolon.csv").read_bytes())
    write("xyz", "raw.xyz", p.astype("<f4").tobytes())
    write("xyz", "text.xyz", (variants / "text.xyz").read_bytes())

    # Houdini JSON geometry: the variants (ASCII tuples/arrays, binary paged in both byte orders, a constant page)
    # and a reduced shared frame in binary JSON.
    for f in sorted(variants.glob("houdini_*")):
        write("houdini", f.name, f.read_bytes())
    write("houdini", "dam26_paged.bgeo", samples.BinaryJson().encode(samples.houdini_geometry(p, i, v, "paged", 4, [1, 2])))

    # Whole-path harness: one seed of every format, some gzip-compressed.
    for harness in ("vtk", "bgeo", "vtu", "ply", "npy", "npz", "csv", "houdini"):
        for f in sorted((CORPUS / harness).iterdir())[:3]:
            write("particles", f"{harness}_{f.name}", f.read_bytes())
    write("particles", "vtk_binary.vtk.gz", gzip.compress(legacy_vtk(p, i, v), mtime=0))
    write("particles", "bgeo.bgeo.gz", gzip.compress((CORPUS / "bgeo" / "dam_break.bgeo").read_bytes(), mtime=0))

    # Meshes: the test meshes and a small binary PLY with normals and an attribute, like write_mesh makes.
    write("mesh", "mixed.obj", (io_data / "mixed.obj").read_bytes())
    write("mesh", "quad_ascii.ply", (io_data / "quad_ascii.ply").read_bytes())
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
              b"property float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float velocity_x\n"
              b"property float velocity_y\nproperty float velocity_z\nelement face 2\n"
              b"property list uchar int vertex_indices\nend_header\n")
    vertices = np.arange(36, dtype="<f4").tobytes()
    faces = b"".join(b"\x03" + np.array(f, "<i4").tobytes() for f in ([0, 1, 2], [0, 2, 3]))
    write("mesh", "binary_mesh.ply", header + vertices + faces)
    # Legacy VTK meshes: the layout write_mesh writes (binary 4.x polygons, normals, SCALARS, VECTORS, FIELD), and
    # ASCII 5.x OFFSETS / CONNECTIVITY with a quad.
    be = lambda values, dtype: np.asarray(values, dtype).tobytes() + b"\n"
    write("mesh", "binary_mesh.vtk",
          b"# vtk DataFile Version 4.2\nmeniscus surface mesh\nBINARY\nDATASET POLYDATA\nPOINTS 4 float\n" +
          be(np.arange(12), ">f4") + b"POLYGONS 2 8\n" + be([3, 0, 1, 2, 3, 0, 2, 3], ">i4") +
          b"POINT_DATA 4\nNORMALS normals float\n" + be(np.ones(12), ">f4") +
          b"SCALARS density float 1\nLOOKUP_TABLE default\n" + be(np.arange(4), ">f4") +
          b"VECTORS velocity float\n" + be(np.arange(12), ">f4") +
          b"FIELD FieldData 1\nuv 2 4 float\n" + be(np.arange(8), ">f4"))
    write("mesh", "ascii_mesh_51.vtk",
          b"# vtk DataFile Version 5.1\nquad\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\n"
          b"POLYGONS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n0 1 2 3\n"
          b"POINT_DATA 4\nNORMALS n float\n0 0 1 0 0 1 0 0 1 0 0 1\n")

    # Mantaflow (Blender's fluid cache): a particle system (12 particles, two flagged), its velocities, a config and a
    # bobj tetrahedron; the harness gives every input to each of the four parsers.
    grid_positions = (p - p.min(axis=0)) / np.ptp(p, axis=0).max() * 7.5 + 0.25
    flags = np.zeros(n, "<i4")
    flags[3], flags[7] = 1, 1 << 10
    system = np.empty(n, [("p", "<f4", (3,)), ("flag", "<i4")])
    system["p"], system["flag"] = grid_positions, flags
    write("mantaflow", "pp_0001.uni", mantaflow_uni(b"PB02", n, 16, system.tobytes()))
    write("mantaflow", "pVel_0001.uni", mantaflow_uni(b"PD01", n, 12, v.astype("<f4").tobytes()))
    write("mantaflow", "config_0001.uni", mantaflow_config())
    tetrahedron = np.array([[0, 0, 0], [0.25, 0, 0], [0, 0.25, 0], [0, 0, 0.2]], "<f4")
    write("mantaflow", "fluid_mesh_0001.bobj",
          struct.pack("<i", 4) + tetrahedron.tobytes() + struct.pack("<i", 4) + tetrahedron.tobytes() +
          struct.pack("<i", 4) + np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], "<i4").tobytes())

    # OpenVDB points: Blender 3.4's Mantaflow bake of the test data (a velocity grid and a point grid in LZ4 Blosc).
    write("vdb", "mantaflow_pool.vdb", (ROOT / "tests/data/mantaflow/cache/data/fluid_data_0001.vdb").read_bytes())
    write("particles", "vdb_mantaflow_pool.vdb", (CORPUS / "vdb" / "mantaflow_pool.vdb").read_bytes())  # by its magic
    # Blosc frames (one block each): BloscLZ with a match, LZ4 with a match, LZ4 byte-shuffled, stored.
    def blosc(flags, typesize, nbytes, stream):
        return (bytes([2, 1, flags, typesize]) + struct.pack("<5I", nbytes, nbytes, 24 + len(stream), 20, len(stream)) +
                bytes(stream))
    write("blosc", "blosclz.blosc", blosc(0x10, 1, 8, [0x02, 97, 98, 99, 0x60, 0x02]))
    write("blosc", "lz4.blosc", blosc(0x30, 1, 10, [0x31, 97, 98, 99, 3, 0, 0x20, 88, 89]))
    write("blosc", "lz4_shuffle.blosc", blosc(0x31, 4, 8, [0x80, 4, 8, 3, 7, 2, 6, 1, 5]))
    write("blosc", "stored.blosc", bytes([2, 1, 2, 1]) + struct.pack("<3I", 3, 3, 19) + b"xyz")

    total = sum(f.stat().st_size for f in CORPUS.rglob("*") if f.is_file())
    print(f"corpus: {sum(1 for f in CORPUS.rglob('*') if f.is_file())} seeds, {total / 1e3:.0f} kB")


if __name__ == "__main__":
    main()
