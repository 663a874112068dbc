"""Writes the OpenVDB test grids scenes/assets/smoke-*.vdb and the same values as a Mitsuba
`.vol` (scenes/assets/smoke-vdb.vol), for pathwave's reader of OpenVDB files
(engine/src/format/vdb.rs) and scenes/smoke-vdb.ron.

OpenVDB itself writes the .vdb files: the `openvdb` module (OpenVDB 12.0, file format 224) that
Blender's `bpy` 5.0.1 bundles. Run with the Python of the environment holding bpy:
    /opt/vdbvenv/bin/python scenes/vdb-make.py

The grid ("density", a fog volume) is a small plume drawn in the 24^3 voxels from index
(-12, 0, 0) to (11, 23, 23); its active voxels span (-10, 0, 1) to (8, 23, 19), 19 x 24 x 19.
It crosses x = 0, so that the tree has two children at its root (x < 0 and x >= 0; each takes
8 KB of masks, hence files of 30 to 64 KB), and it has internal nodes, 30 leaves, an active
tile (a constant 8^3 core), an inactive tile of faint haze, and leaves whose inactive voxels
hold zero, one or more haze values (OpenVDB's active-mask kinds 0, 2, 4, 5 and 6; 1 and 3
need a background other than 0). Densities are multiples of 1/1024 in [0, 1], which IEEE half
floats hold exactly, so the half-float file has the same values as the others. Its transform:
voxels of 0.05 with the index origin at (0.1, 0, -0.2) in world space
(UniformScaleTranslateMap).

Files (the compression flags that OpenVDB writes for each grid: io/Compression.h):
    smoke-blosc.vdb       Blosc (LZ4, byte shuffle) + active mask: OpenVDB's default. Also holds
                          "temperature" (float, 2 at one voxel), "velocity" (vec3s),
                          "id" (int32), for grid selection and the errors of other types,
                          and "instance", the density's tree under voxels of 0.1.
    smoke-zip.vdb         zlib + active mask.
    smoke-zip-nomask.vdb  zlib, no active-mask compression (every value written).
    smoke-none.vdb        active mask only, values uncompressed.
    smoke-half.vdb        Blosc + active mask, values stored as half floats (`_HalfFloat`).
    smoke-vdb.vol         the dense values over the active voxels' bounding box (x fastest),
                          bounding box (0, 0, 0)-(1, 1, 1).

The Python module always writes with OpenVDB's default compression (io::File::setCompression
is not exposed), so the other compressions are chosen by what setCompression would change:
a small library, compiled here with g++ and preloaded into a child Python, replaces OpenVDB's
`io::Archive::setGridCompression` (which writes each grid's flags and tags the stream with
them) by one that writes the flags in $VDB_COMPRESSION. Every file is read back with OpenVDB
and its dense values checked against the .vol's.
"""
import glob
import math
import os
import struct
import subprocess
import sys
import tempfile

SITE = glob.glob("/opt/vdbvenv/lib/python3*/site-packages/bpy/5.0/python/lib/python3.11/site-packages")
LIB = glob.glob("/opt/vdbvenv/lib/python3*/site-packages/bpy/lib")

# The box the plume is drawn in (its active voxels fill a little less).
LO = (-12, 0, 0)
N = 24
HI = tuple(c + N - 1 for c in LO)

# The flags of io/Compression.h.
ZIP, ACTIVE_MASK, BLOSC = 0x1, 0x2, 0x4
FILES = {
    "smoke-blosc.vdb": (BLOSC | ACTIVE_MASK, False),
    "smoke-zip.vdb": (ZIP | ACTIVE_MASK, False),
    "smoke-zip-nomask.vdb": (ZIP, False),
    "smoke-none.vdb": (ACTIVE_MASK, False),
    "smoke-half.vdb": (BLOSC | ACTIVE_MASK, True),
}

SHIM = r"""
#include <cstdint>
#include <cstdlib>
#include <ostream>
namespace openvdb { namespace v12_0 {
class GridBase;
namespace io {
void setDataCompression(std::ios_base&, unsigned int);
class Archive { public: void setGridCompression(std::ostream&, const GridBase&) const; };
void Archive::setGridCompression(std::ostream& os, const GridBase&) const {
    uint32_t c = uint32_t(std::strtoul(std::getenv("VDB_COMPRESSION"), nullptr, 0));
    setDataCompression(os, c);
    os.write(reinterpret_cast<const char*>(&c), sizeof c);
}
}}}
"""


def density(i, j, k):
    """The plume's density at index (i, j, k), a multiple of 1/1024 in [0, 1]."""
    u, v, w = [(c - lo + 0.5) / N for c, lo in zip((i, j, k), LO)]
    cx = 0.5 + 0.12 * math.sin(3.0 * v + 0.5) * v
    cz = 0.5 + 0.08 * math.cos(4.0 * v) * v
    r = math.hypot(u - cx, w - cz) / (0.1 + 0.3 * v)
    core = max(0.0, 1.0 - r * r)
    swirl = 0.55 + 0.45 * math.sin(9.0 * u + 7.0 * v) * math.cos(8.0 * w - 5.0 * v + 1.3)
    fade = min(1.0, 6.0 * v) * min(1.0, 5.0 * (1.0 - v))
    return round(1024 * max(0.0, min(1.0, core * swirl * fade))) / 1024


def haze(i, j, k):
    """What an inactive voxel holds: 0 (the background) in most of the box, faint haze of one
    or two values (1/1024, 2/1024) in bands, and three values in one corner: leaves of every
    kind of active-mask compression."""
    if i < -4 and k > 12:
        return (1 + (i + j + k) % 3) / 1024
    if j >= 16 and i >= 4:
        return (1 + (j // 2) % 2) / 1024
    if k < 8:
        return 1 / 1024
    return 0.0


def build(vdb):
    """The grids of the files."""
    grid = vdb.FloatGrid(0.0)
    grid.name = "density"
    grid.gridClass = "fog volume"
    acc = grid.getAccessor()
    for i in range(LO[0], HI[0] + 1):
        for j in range(LO[1], HI[1] + 1):
            for k in range(LO[2], HI[2] + 1):
                d = density(i, j, k)
                if d >= 4 / 1024:
                    acc.setValueOn((i, j, k), d)
                elif haze(i, j, k) != 0.0:
                    acc.setValueOff((i, j, k), haze(i, j, k))
    # A constant core (an active tile of a leaf's size, 8^3 voxels) and a block of faint haze
    # (an inactive tile) inside the box.
    grid.fill((-8, 8, 8), (-1, 15, 15), 0.5, True)
    grid.fill((0, 0, 8), (7, 7, 15), 3 / 1024, False)
    grid.transform = vdb.createLinearTransform(0.05)
    grid.transform.postTranslate((0.1, 0.0, -0.2))

    temperature = vdb.FloatGrid(0.0)
    temperature.name = "temperature"
    temperature.getAccessor().setValueOn((0, 4, 0), 2.0)
    velocity = vdb.Vec3SGrid()
    velocity.name = "velocity"
    velocity.getAccessor().setValueOn((0, 4, 0), (0.0, 1.0, 0.0))
    ids = vdb.Int32Grid()
    ids.name = "id"
    ids.getAccessor().setValueOn((0, 4, 0), 7)
    # A grid sharing the density's tree (OpenVDB writes it as an instance: no tree of its own)
    # under voxels twice the size.
    instance = grid.copy()
    instance.name = "instance"
    instance.transform = vdb.createLinearTransform(0.1)
    return grid, [temperature, velocity, ids, instance]


def dense(grid, box):
    """The grid's values over the index box `(lo, hi)` (inclusive), x fastest (as a .vol holds
    them)."""
    (lo, hi), acc = box, grid.getConstAccessor()
    return [acc.getValue((i, j, k))
            for k in range(lo[2], hi[2] + 1)
            for j in range(lo[1], hi[1] + 1)
            for i in range(lo[0], hi[0] + 1)]


def write(path, half, extra):
    """In the child: writes one file with the flags in $VDB_COMPRESSION."""
    import openvdb as vdb
    grid, others = build(vdb)
    grid.saveFloatAsHalf = half
    vdb.write(path, [grid] + (others if extra else []))


def main():
    sys.path.insert(0, SITE[0])
    if sys.argv[1:2] == ["--write"]:
        write(sys.argv[2], sys.argv[3] == "half", sys.argv[4] == "extra")
        return
    import openvdb as vdb
    out = "scenes/assets"
    with tempfile.TemporaryDirectory() as tmp:
        shim = os.path.join(tmp, "compression.so")
        with open(os.path.join(tmp, "compression.cpp"), "w") as f:
            f.write(SHIM)
        subprocess.run(["g++", "-O1", "-shared", "-fPIC", f.name, "-o", shim, f"-L{LIB[0]}",
                        "-l:libopenvdb.so.12.0", f"-Wl,-rpath,{LIB[0]}"], check=True)
        for name, (flags, half) in FILES.items():
            env = dict(os.environ, LD_PRELOAD=shim, VDB_COMPRESSION=str(flags))
            path = os.path.join(out, name)
            args = [sys.executable, __file__, "--write", path, "half" if half else "full",
                    "extra" if name == "smoke-blosc.vdb" else "alone"]
            subprocess.run(args, env=env, check=True, stderr=subprocess.DEVNULL)

    grid, _ = build(vdb)
    box = grid.evalActiveVoxelBoundingBox()
    size = [h - l + 1 for l, h in zip(*box)]
    values = dense(grid, box)
    with open(os.path.join(out, "smoke-vdb.vol"), "wb") as f:
        f.write(b"VOL" + bytes([3]))
        f.write(struct.pack("<5i", 1, *size, 1))
        f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        f.write(struct.pack(f"<{len(values)}f", *values))
    for name in FILES:
        back = vdb.read(os.path.join(out, name), "density")
        assert back.evalActiveVoxelBoundingBox() == box, name
        assert dense(back, box) == values, name
        nbytes = os.path.getsize(os.path.join(out, name))
        meta = vdb.readGridMetadata(os.path.join(out, name), "density")
        print(f"{name}: {nbytes} bytes, {meta['file_compression']}, {back.leafCount()} leaves")
    corner = grid.transform.indexToWorld(box[0])
    print(f"active box {box} ({size}), {sum(v > 0 for v in values)} non-zero values; "
          f"index {box[0]} at world {corner}")


if __name__ == "__main__":
    main()
