// OpenVDB's counterparts of `pgvol encode` and `pgvol decode` as one native process each, so that
// bench_scale.py times both tools from outside without an interpreter's start-up on either side.
//
//   vdb_driver encode MESH.obj OUT.vdb --voxel V [--origin X Y Z] [--band 3]
//   vdb_driver decode IN.vdb OUT.ply
//   vdb_driver version
//
// encode: reads the OBJ (positions and faces; triangles and quads are passed as they are, larger
// polygons as fans; normals, texture coordinates and everything else ignored), runs
// tools::meshToLevelSet with a half-width of --band voxels on a linear transform of voxel size V
// whose voxel (0, 0, 0) is at --origin (default: the world origin), and writes the grid, named
// "surface", with the library's default compression.
// decode: reads the first grid of the file, runs tools::volumeToMesh at isovalue 0 with
// adaptivity 0, and writes a binary little-endian PLY (float x y z, uchar/int index lists) of
// triangles, each quad split in two, wound outward.
// Each prints one JSON line: the seconds of its stages (read, compute, write) and counts.
//
// Build: make -C tools/bench/vdb_driver (Debian's libopenvdb-dev and g++).

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

const char* version() { return openvdb::getLibraryVersionString(); }

std::vector<char> slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw std::runtime_error("cannot open " + path);
    std::vector<char> data(static_cast<size_t>(in.tellg()) + 1);
    in.seekg(0);
    in.read(data.data(), static_cast<std::streamsize>(data.size() - 1));
    if (!in) throw std::runtime_error("cannot read " + path);
    data.back() = '\0';  // strtof/strtol stop at it
    return data;
}

struct Mesh {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
};

// Positions ("v x y z") and faces ("f a b c [d ...]", each corner "i", "i/t", "i//n" or "i/t/n",
// negative indices relative to the vertices read so far). Other lines are skipped.
Mesh readObj(const std::string& path) {
    std::vector<char> data = slurp(path);
    Mesh mesh;
    const char* p = data.data();
    const char* end = p + data.size() - 1;
    std::vector<long> corners;
    size_t line = 0;
    auto fail = [&](const char* what) {
        throw std::runtime_error(path + ":" + std::to_string(line) + ": " + what);
    };
    while (p < end) {
        ++line;
        const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
        if (!eol) eol = end;
        while (p < eol && (*p == ' ' || *p == '\t')) ++p;
        if (eol - p > 1 && p[0] == 'v' && (p[1] == ' ' || p[1] == '\t')) {
            char* q = const_cast<char*>(p + 1);
            float xyz[3];
            for (float& c : xyz) {
                char* next;
                c = std::strtof(q, &next);
                if (next == q || next > eol) fail("a vertex needs three coordinates");
                q = next;
            }
            mesh.points.emplace_back(xyz[0], xyz[1], xyz[2]);
        } else if (eol - p > 1 && p[0] == 'f' && (p[1] == ' ' || p[1] == '\t')) {
            corners.clear();
            char* q = const_cast<char*>(p + 1);
            while (true) {
                while (q < eol && (*q == ' ' || *q == '\t' || *q == '\r')) ++q;
                if (q >= eol) break;
                char* next;
                long i = std::strtol(q, &next, 10);
                if (next == q) fail("a face corner needs a vertex index");
                q = next;
                while (q < eol && *q != ' ' && *q != '\t' && *q != '\r') ++q;  // "/t/n"
                long n = static_cast<long>(mesh.points.size());
                long idx = i > 0 ? i - 1 : n + i;
                if (i == 0 || idx < 0 || idx >= n) fail("a face refers to a vertex not read yet");
                corners.push_back(idx);
            }
            auto at = [&](size_t k) { return static_cast<openvdb::Index32>(corners[k]); };
            if (corners.size() == 4) {
                mesh.quads.emplace_back(at(0), at(1), at(2), at(3));
            } else if (corners.size() >= 3) {
                for (size_t k = 1; k + 1 < corners.size(); ++k) mesh.triangles.emplace_back(at(0), at(k), at(k + 1));
            } else {
                fail("a face needs three corners or more");
            }
        }
        p = eol + 1;
    }
    return mesh;
}

void writePly(const std::string& path, const std::vector<openvdb::Vec3s>& points,
              const std::vector<openvdb::Vec3I>& triangles, const std::vector<openvdb::Vec4I>& quads) {
    const uint32_t probe = 1;
    if (*reinterpret_cast<const unsigned char*>(&probe) != 1) throw std::runtime_error("big-endian host");
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw std::runtime_error("cannot create " + path);
    std::vector<char> buffer(1 << 22);
    std::setvbuf(f, buffer.data(), _IOFBF, buffer.size());
    const size_t faces = triangles.size() + 2 * quads.size();
    std::fprintf(f,
                 "ply\nformat binary_little_endian 1.0\nelement vertex %zu\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 "element face %zu\nproperty list uchar int vertex_indices\nend_header\n",
                 points.size(), faces);
    static_assert(sizeof(openvdb::Vec3s) == 12, "Vec3s is three packed floats");
    std::fwrite(points.data(), sizeof(openvdb::Vec3s), points.size(), f);
    // volumeToMesh winds its faces inward: each is written reversed.
    std::vector<unsigned char> block;
    block.reserve(13 * 65536);
    auto put = [&](uint32_t a, uint32_t b, uint32_t c) {
        unsigned char rec[13];
        rec[0] = 3;
        std::memcpy(rec + 1, &a, 4);
        std::memcpy(rec + 5, &b, 4);
        std::memcpy(rec + 9, &c, 4);
        block.insert(block.end(), rec, rec + 13);
        if (block.size() >= 13 * 65536) {
            std::fwrite(block.data(), 1, block.size(), f);
            block.clear();
        }
    };
    for (const auto& t : triangles) put(t[2], t[1], t[0]);
    for (const auto& q : quads) {
        put(q[0], q[2], q[1]);
        put(q[0], q[3], q[2]);
    }
    std::fwrite(block.data(), 1, block.size(), f);
    if (std::fclose(f) != 0) throw std::runtime_error("cannot write " + path);
}

size_t fileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    return in ? static_cast<size_t>(in.tellg()) : 0;
}

int encode(const std::string& meshPath, const std::string& out, double voxel, const openvdb::Vec3d& origin,
           float band) {
    auto t0 = Clock::now();
    Mesh mesh = readObj(meshPath);
    if (mesh.triangles.empty() && mesh.quads.empty()) throw std::runtime_error(meshPath + " has no faces");
    double read = since(t0);

    auto t1 = Clock::now();
    // Voxel (i, j, k) at origin + voxel * (i, j, k).
    openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(voxel);
    xform->postTranslate(origin);
    openvdb::FloatGrid::Ptr grid =
        openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, mesh.points, mesh.triangles, mesh.quads, band);
    grid->setName("surface");
    double compute = since(t1);

    auto t2 = Clock::now();
    openvdb::GridPtrVec grids{grid};
    openvdb::io::File file(out);
    file.write(grids);
    file.close();
    double write = since(t2);

    std::printf(
        "{\"stage\": \"encode\", \"read\": %.6f, \"compute\": %.6f, \"write\": %.6f, \"vertices\": %zu, "
        "\"triangles\": %zu, \"quads\": %zu, \"voxel\": %.17g, \"band\": %g, \"active_voxels\": %llu, "
        "\"bytes\": %zu, \"openvdb\": \"%s\"}\n",
        read, compute, write, mesh.points.size(), mesh.triangles.size(), mesh.quads.size(), voxel, band,
        static_cast<unsigned long long>(grid->activeVoxelCount()), fileBytes(out), version());
    return 0;
}

int decode(const std::string& in, const std::string& out) {
    auto t0 = Clock::now();
    openvdb::io::File file(in);
    file.open();
    openvdb::GridPtrVecPtr grids = file.getGrids();
    file.close();
    openvdb::FloatGrid::Ptr grid;
    for (const auto& base : *grids) {
        if ((grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base))) break;
    }
    if (!grid) throw std::runtime_error(in + " has no float grid");
    double read = since(t0);

    auto t1 = Clock::now();
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*grid, points, triangles, quads, /*isovalue=*/0.0, /*adaptivity=*/0.0);
    double compute = since(t1);

    auto t2 = Clock::now();
    writePly(out, points, triangles, quads);
    double write = since(t2);

    std::printf(
        "{\"stage\": \"decode\", \"read\": %.6f, \"compute\": %.6f, \"write\": %.6f, \"vertices\": %zu, "
        "\"triangles\": %zu, \"bytes\": %zu, \"openvdb\": \"%s\"}\n",
        read, compute, write, points.size(), triangles.size() + 2 * quads.size(), fileBytes(out),
        version());
    return 0;
}

[[noreturn]] void usage() {
    std::fprintf(stderr,
                 "usage: vdb_driver encode MESH.obj OUT.vdb --voxel V [--origin X Y Z] [--band 3]\n"
                 "       vdb_driver decode IN.vdb OUT.ply\n"
                 "       vdb_driver version\n");
    std::exit(2);
}

double number(const char* text) {
    char* end;
    double v = std::strtod(text, &end);
    if (end == text || *end != '\0') usage();
    return v;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) usage();
    const std::string mode = argv[1];
    try {
        if (mode == "version") {
            std::printf("{\"openvdb\": \"%s\"}\n", version());
            return 0;
        }
        openvdb::initialize();
        if (mode == "encode") {
            if (argc < 4) usage();
            double voxel = 0.0;
            float band = 3.0f;
            openvdb::Vec3d origin(0.0);
            for (int i = 4; i < argc; ++i) {
                const std::string opt = argv[i];
                if (opt == "--voxel" && i + 1 < argc) {
                    voxel = number(argv[++i]);
                } else if (opt == "--band" && i + 1 < argc) {
                    band = static_cast<float>(number(argv[++i]));
                } else if (opt == "--origin" && i + 3 < argc) {
                    for (int k = 0; k < 3; ++k) origin[k] = number(argv[++i]);
                } else {
                    usage();
                }
            }
            if (!(voxel > 0.0) || !(band >= 1.0f)) usage();
            return encode(argv[2], argv[3], voxel, origin, band);
        }
        if (mode == "decode" && argc == 4) return decode(argv[2], argv[3]);
        usage();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vdb_driver %s: %s\n", mode.c_str(), e.what());
        return 1;
    }
}
