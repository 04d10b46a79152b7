// Mesh loading (every format), validation (every fault reported, one line, naming file and
// place) and topology (edge and vertex convexity on shapes with known answers).
#include "sulcus/engine/mesh.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <unistd.h>

namespace sulcus {
namespace {

namespace fs = std::filesystem;

// 2^-7 m: a tooth-sized cube whose coordinates are exact in float and in decimal text, so every
// format (binary STL and glTF store float) gives the same volume.
constexpr double kSide = 0.0078125;

// Quads wound counter-clockwise seen from outside.
const std::array<std::array<uint32_t, 4>, 6> kCubeQuads = {{
    {0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 4, 7, 3}, {1, 2, 6, 5}}};

TriMesh cube(double side = kSide, Vec3 origin = Vec3(0.0)) {
    TriMesh m;
    for (int i = 0; i < 8; ++i) {
        const double x = (i == 1 || i == 2 || i == 5 || i == 6) ? side : 0.0;
        const double y = (i == 2 || i == 3 || i == 6 || i == 7) ? side : 0.0;
        const double z = i >= 4 ? side : 0.0;
        m.vertices.push_back(origin + Vec3(x, y, z));
    }
    for (const auto& q : kCubeQuads) {
        m.triangles.push_back({q[0], q[1], q[2]});
        m.triangles.push_back({q[0], q[2], q[3]});
    }
    return m;
}

// A prism over a counter-clockwise polygon in the xy plane, with the given cap triangulation.
TriMesh prism(const std::vector<glm::dvec2>& poly, const std::vector<std::array<uint32_t, 3>>& cap, double h) {
    TriMesh m;
    const uint32_t n = uint32_t(poly.size());
    for (const auto& p : poly) m.vertices.push_back(Vec3(p.x, p.y, 0.0));
    for (const auto& p : poly) m.vertices.push_back(Vec3(p.x, p.y, h));
    for (const auto& t : cap) {
        m.triangles.push_back({t[0], t[2], t[1]});
        m.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
    }
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t j = (i + 1) % n;
        m.triangles.push_back({i, j, j + n});
        m.triangles.push_back({i, j + n, i + n});
    }
    return m;
}

std::string obj_text(const TriMesh& m) {
    std::ostringstream s;
    s.precision(17);
    s << "# test mesh\no test\n";
    for (const Vec3& p : m.vertices) s << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    for (const auto& t : m.triangles) s << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    return s.str();
}

std::string off_text(const TriMesh& m) {
    std::ostringstream s;
    s.precision(17);
    s << "OFF\n# comment\n" << m.vertices.size() << ' ' << m.triangles.size() << " 0\n";
    for (const Vec3& p : m.vertices) s << p.x << ' ' << p.y << ' ' << p.z << '\n';
    for (const auto& t : m.triangles) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
    return s.str();
}

// Quads where possible, to exercise polygon faces.
std::string ply_text(const TriMesh& m, bool quads) {
    std::ostringstream s;
    s.precision(17);
    const size_t faces = quads ? 6 : m.triangles.size();
    s << "ply\nformat ascii 1.0\ncomment test\nelement vertex " << m.vertices.size()
      << "\nproperty double x\nproperty double y\nproperty double z\nelement face " << faces
      << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const Vec3& p : m.vertices) s << p.x << ' ' << p.y << ' ' << p.z << '\n';
    if (quads)
        for (const auto& q : kCubeQuads) s << "4 " << q[0] << ' ' << q[1] << ' ' << q[2] << ' ' << q[3] << '\n';
    else
        for (const auto& t : m.triangles) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
    return s.str();
}

Vec3 face_normal(const TriMesh& m, const std::array<uint32_t, 3>& t) {
    const Vec3 n = glm::cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]);
    const double l = glm::length(n);
    return l > 0 ? n / l : Vec3(0.0);
}

std::string stl_ascii(const TriMesh& m) {
    std::ostringstream s;
    s.precision(17);
    s << "solid test\n";
    for (const auto& t : m.triangles) {
        const Vec3 n = face_normal(m, t);
        s << "  facet normal " << n.x << ' ' << n.y << ' ' << n.z << "\n    outer loop\n";
        for (uint32_t v : t) s << "      vertex " << m.vertices[v].x << ' ' << m.vertices[v].y << ' ' << m.vertices[v].z << '\n';
        s << "    endloop\n  endfacet\n";
    }
    s << "endsolid test\n";
    return s.str();
}

template <class T>
void put(std::string& out, T value) {
    out.append(reinterpret_cast<const char*>(&value), sizeof value);
}

std::string stl_binary(const TriMesh& m) {
    std::string out(80, ' ');
    out.replace(0, 11, "binary test");
    put(out, uint32_t(m.triangles.size()));
    for (const auto& t : m.triangles) {
        const Vec3 n = face_normal(m, t);
        for (int i = 0; i < 3; ++i) put(out, float(n[i]));
        for (uint32_t v : t)
            for (int i = 0; i < 3; ++i) put(out, float(m.vertices[v][i]));
        put(out, uint16_t(0));
    }
    return out;
}

std::string base64(const std::string& in) {
    static const char* chars = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        const uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8 | uint8_t(in[i + 2]);
        for (int k = 3; k >= 0; --k) out += chars[(v >> (6 * k)) & 63];
    }
    if (i + 1 == in.size()) {
        const uint32_t v = uint32_t(uint8_t(in[i])) << 16;
        out += chars[(v >> 18) & 63];
        out += chars[(v >> 12) & 63];
        out += "==";
    } else if (i + 2 == in.size()) {
        const uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8;
        out += chars[(v >> 18) & 63];
        out += chars[(v >> 12) & 63];
        out += chars[(v >> 6) & 63];
        out += '=';
    }
    return out;
}

// glTF of a mesh as one primitive: float positions then indices of the given component type
// (5121 ubyte, 5123 ushort, 5125 uint) in one buffer; `node` holds the node's transform keys.
struct Gltf {
    nlohmann::json json;
    std::string bin;
};

Gltf gltf_of(const TriMesh& m, int index_type, const nlohmann::json& node) {
    Gltf g;
    for (const Vec3& p : m.vertices)
        for (int i = 0; i < 3; ++i) put(g.bin, float(p[i]));
    const size_t positions_bytes = g.bin.size();
    for (const auto& t : m.triangles)
        for (uint32_t v : t) {
            if (index_type == 5121) put(g.bin, uint8_t(v));
            else if (index_type == 5123) put(g.bin, uint16_t(v));
            else put(g.bin, uint32_t(v));
        }
    const size_t index_bytes = g.bin.size() - positions_bytes;
    while (g.bin.size() % 4) g.bin += '\0';
    nlohmann::json n = node;
    n["mesh"] = 0;
    using nlohmann::json;
    json primitive = {{"attributes", {{"POSITION", 0}}}, {"indices", 1}, {"mode", 4}};
    json positions = {{"bufferView", 0}, {"componentType", 5126}, {"count", m.vertices.size()}, {"type", "VEC3"}};
    json indices = {{"bufferView", 1}, {"componentType", index_type}, {"count", 3 * m.triangles.size()},
                    {"type", "SCALAR"}};
    json position_view = {{"buffer", 0}, {"byteOffset", 0}, {"byteLength", positions_bytes}};
    json index_view = {{"buffer", 0}, {"byteOffset", positions_bytes}, {"byteLength", index_bytes}};
    json root_node = {{"children", json::array({1})}};
    g.json = json::object();
    g.json["asset"] = {{"version", "2.0"}};
    g.json["scene"] = 0;
    g.json["scenes"] = json::array({json{{"nodes", json::array({0})}}});
    g.json["nodes"] = json::array({root_node, n});
    g.json["meshes"] = json::array({json{{"primitives", json::array({primitive})}}});
    g.json["accessors"] = json::array({positions, indices});
    g.json["bufferViews"] = json::array({position_view, index_view});
    g.json["buffers"] = json::array({json{{"byteLength", g.bin.size()}}});
    return g;
}

std::string gltf_text(Gltf g) {
    g.json["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(g.bin);
    return g.json.dump(1);
}

std::string glb_bytes(const Gltf& g) {
    std::string json = g.json.dump();
    while (json.size() % 4) json += ' ';
    std::string out;
    put(out, uint32_t(0x46546C67));  // "glTF"
    put(out, uint32_t(2));
    put(out, uint32_t(12 + 8 + json.size() + 8 + g.bin.size()));
    put(out, uint32_t(json.size()));
    put(out, uint32_t(0x4E4F534A));  // "JSON"
    out += json;
    put(out, uint32_t(g.bin.size()));
    put(out, uint32_t(0x004E4942));  // "BIN"
    out += g.bin;
    return out;
}

class MeshFiles : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = fs::temp_directory_path() / ("sulcus_test_mesh_" + std::to_string(::getpid()));
        fs::create_directories(dir_);
    }
    static void TearDownTestSuite() { fs::remove_all(dir_); }

    static std::string write(const std::string& name, const std::string& content) {
        const fs::path p = dir_ / name;
        std::ofstream(p, std::ios::binary) << content;
        return p.string();
    }
    static inline fs::path dir_;
};

// A load error must name the file first and stay on one line.
void expect_error(const MeshLoad& load, const std::string& path, const std::string& fault) {
    EXPECT_FALSE(load.ok()) << path;
    EXPECT_EQ(load.error.rfind(path + ": ", 0), 0u) << load.error;
    EXPECT_NE(load.error.find(fault), std::string::npos) << "expected '" << fault << "' in: " << load.error;
    EXPECT_EQ(load.error.find('\n'), std::string::npos) << load.error;
    EXPECT_EQ(load.error.find('\r'), std::string::npos) << load.error;
    EXPECT_TRUE(load.mesh.triangles.empty());
}

// ---- loading ------------------------------------------------------------------------------------

TEST_F(MeshFiles, EveryFormatLoadsTheCubeWithTheSameVolume) {
    const TriMesh c = cube();
    const nlohmann::json identity = nlohmann::json::object();
    const std::vector<std::pair<std::string, std::string>> files = {
        {"cube.obj", obj_text(c)},
        {"cube.off", off_text(c)},
        {"cube_ascii.stl", stl_ascii(c)},
        {"cube_binary.stl", stl_binary(c)},
        {"cube_quads.ply", ply_text(c, true)},
        {"cube_tris.ply", ply_text(c, false)},
        {"cube.gltf", gltf_text(gltf_of(c, 5123, identity))},
        {"cube.glb", glb_bytes(gltf_of(c, 5125, identity))},
    };
    const double expected = kSide * kSide * kSide;
    for (const auto& [name, content] : files) {
        const MeshLoad load = load_mesh(write(name, content));
        ASSERT_TRUE(load.ok()) << name << ": " << load.error;
        EXPECT_EQ(load.mesh.vertices.size(), 8u) << name;
        EXPECT_EQ(load.mesh.triangles.size(), 12u) << name;
        EXPECT_DOUBLE_EQ(mesh_volume(load.mesh), expected) << name;
        EXPECT_EQ(validate_mesh(load.mesh), "") << name;
    }
}

TEST_F(MeshFiles, UppercaseExtensionIsRecognised) {
    const MeshLoad load = load_mesh(write("CUBE.OBJ", obj_text(cube())));
    EXPECT_TRUE(load.ok()) << load.error;
}

TEST_F(MeshFiles, ObjPolygonsRelativeIndicesAndAttributesAreRead) {
    // Quads with texture/normal references, negative (relative) indices, CRLF line ends, a BOM.
    std::string text = "\xEF\xBB\xBFmtllib x.mtl\r\n";
    for (const Vec3& p : cube().vertices) {
        std::ostringstream v;
        v.precision(17);
        v << "v " << p.x << ' ' << p.y << ' ' << p.z << "\r\nvt 0 0\r\nvn 0 0 1\r\n";
        text += v.str();
    }
    text += "g cube\r\nusemtl none\r\ns off\r\n";
    for (const auto& q : kCubeQuads) {
        text += "f";
        for (uint32_t v : q) text += " " + std::to_string(int(v) - 8) + "/1/1";
        text += "\r\n";
    }
    const MeshLoad load = load_mesh(write("polygons.obj", text));
    ASSERT_TRUE(load.ok()) << load.error;
    EXPECT_EQ(load.mesh.triangles.size(), 12u);
    EXPECT_DOUBLE_EQ(mesh_volume(load.mesh), kSide * kSide * kSide);
}

TEST_F(MeshFiles, BinaryStlWhoseHeaderStartsWithSolidIsBinary) {
    std::string bytes = stl_binary(cube());
    bytes.replace(0, 11, "solid cube ");
    const MeshLoad load = load_mesh(write("solid_header.stl", bytes));
    ASSERT_TRUE(load.ok()) << load.error;
    EXPECT_DOUBLE_EQ(mesh_volume(load.mesh), kSide * kSide * kSide);
}

TEST_F(MeshFiles, SplitVerticesOfPerFaceFormatsAreWelded) {
    // Binary STL and non-indexed glTF repeat each corner per triangle: 36 corners -> 8 vertices.
    TriMesh soup;
    const TriMesh c = cube();
    for (const auto& t : c.triangles) {
        const uint32_t base = uint32_t(soup.vertices.size());
        for (uint32_t v : t) soup.vertices.push_back(c.vertices[v]);
        soup.triangles.push_back({base, base + 1, base + 2});
    }
    const MeshLoad load = load_mesh(write("soup.gltf", gltf_text(gltf_of(soup, 5125, nlohmann::json::object()))));
    ASSERT_TRUE(load.ok()) << load.error;
    EXPECT_EQ(load.mesh.vertices.size(), 8u);
}

TEST_F(MeshFiles, GltfAppliesNodeTransformsForEveryIndexType) {
    const TriMesh c = cube();
    const double s = kSide;
    for (int index_type : {5121, 5123, 5125}) {
        // Translation plus a scale of 2: the volume grows 8 times and the box moves.
        const nlohmann::json trs = {{"translation", {1.0, 2.0, 3.0}}, {"scale", {2.0, 2.0, 2.0}}};
        const MeshLoad load = load_mesh(write("trs.gltf", gltf_text(gltf_of(c, index_type, trs))));
        ASSERT_TRUE(load.ok()) << index_type << ": " << load.error;
        EXPECT_DOUBLE_EQ(mesh_volume(load.mesh), 8 * s * s * s);
        Aabb box;
        for (const Vec3& p : load.mesh.vertices) box.grow(p);
        EXPECT_EQ(box.lo, Vec3(1.0, 2.0, 3.0));
        EXPECT_EQ(box.hi, Vec3(1.0 + 2 * s, 2.0 + 2 * s, 3.0 + 2 * s));
    }
    // A quarter turn about y given as a matrix (column-major): x -> -z.
    const nlohmann::json matrix = {{"matrix", {0, 0, -1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1}}};
    const MeshLoad turned = load_mesh(write("matrix.gltf", gltf_text(gltf_of(c, 5123, matrix))));
    ASSERT_TRUE(turned.ok()) << turned.error;
    Aabb box;
    for (const Vec3& p : turned.mesh.vertices) box.grow(p);
    EXPECT_EQ(box.lo, Vec3(0.0, 0.0, -s));
    // A mirroring scale reverses winding; the loader keeps the normals outward.
    const nlohmann::json mirror = {{"scale", {-1.0, 1.0, 1.0}}};
    const MeshLoad mirrored = load_mesh(write("mirror.gltf", gltf_text(gltf_of(c, 5123, mirror))));
    ASSERT_TRUE(mirrored.ok()) << mirrored.error;
    EXPECT_DOUBLE_EQ(mesh_volume(mirrored.mesh), s * s * s);
}

TEST_F(MeshFiles, GltfWithoutTrianglesOrWithBadIndicesIsRejected) {
    Gltf lines = gltf_of(cube(), 5123, nlohmann::json::object());
    lines.json["meshes"][0]["primitives"][0]["mode"] = 1;
    std::string path = write("lines.gltf", gltf_text(lines));
    expect_error(load_mesh(path), path, "mode 1");

    TriMesh bad = cube();
    bad.triangles[3][1] = 8;
    path = write("bad_index.gltf", gltf_text(gltf_of(bad, 5123, nlohmann::json::object())));
    expect_error(load_mesh(path), path, "out of range");

    path = write("broken.glb", "glTF garbage that is not a binary container");
    const MeshLoad load = load_mesh(path);
    EXPECT_FALSE(load.ok());
    EXPECT_EQ(load.error.find('\n'), std::string::npos) << load.error;
}

TEST_F(MeshFiles, WriteObjRoundTripsExactly) {
    TriMesh m = cube(0.1, Vec3(0.1, 1.0 / 3.0, -2e-7));
    const std::string path = (dir_ / "written.obj").string();
    std::string error;
    ASSERT_TRUE(write_obj(m, path, &error)) << error;
    EXPECT_FALSE(fs::exists(path + ".tmp"));
    const MeshLoad load = load_mesh(path);
    ASSERT_TRUE(load.ok()) << load.error;
    EXPECT_EQ(load.mesh.vertices, m.vertices);
    EXPECT_EQ(load.mesh.triangles, m.triangles);

    EXPECT_FALSE(write_obj(m, (dir_ / "no_such_dir" / "x.obj").string(), &error));
    EXPECT_NE(error.find("no_such_dir"), std::string::npos) << error;
}

// ---- broken files -------------------------------------------------------------------------------

TEST_F(MeshFiles, MissingUnknownEmptyAndGarbageFilesAreReported) {
    std::string path = (dir_ / "does_not_exist.obj").string();
    expect_error(load_mesh(path), path, "No such file");

    path = write("cube.xyz", obj_text(cube()));
    expect_error(load_mesh(path), path, "unknown mesh format");

    for (const char* ext : {".obj", ".off", ".stl", ".ply", ".gltf", ".glb"}) {
        path = write(std::string("empty") + ext, "");
        expect_error(load_mesh(path), path, "empty file");
        path = write(std::string("garbage") + ext, "this is not a mesh\n\x01\x02 at all {[\n");
        const MeshLoad load = load_mesh(path);
        expect_error(load, path, "");
        EXPECT_GT(load.error.size(), path.size() + 4) << load.error;
    }
    path = write("garbage.obj", "this is not a mesh\n");
    expect_error(load_mesh(path), path, "line 1: unknown statement 'this'");
    path = write("garbage.off", "this is not a mesh\n");
    expect_error(load_mesh(path), path, "line 1: missing OFF header");
}

// Broken variants of the cube, each with the fault the message must name.
struct Broken {
    std::string name;
    TriMesh mesh;
    std::string fault;
};

std::vector<Broken> broken_cubes() {
    std::vector<Broken> out;
    TriMesh m = cube();
    m.triangles.pop_back();
    m.triangles.pop_back();
    out.push_back({"open", m, "open boundary at edge"});

    m = cube();
    std::swap(m.triangles[5][1], m.triangles[5][2]);
    out.push_back({"flipped", m, "triangle 5: inconsistent orientation"});

    m = cube();
    m.triangles.push_back(m.triangles[7]);
    out.push_back({"duplicate", m, "triangle 12: duplicate of triangle 7"});

    m = cube();
    m.triangles.push_back({2, 2, 5});
    out.push_back({"repeated_vertex", m, "triangle 12: degenerate (vertex 2 used twice)"});

    m = cube();
    m.vertices.push_back(0.5 * (m.vertices[0] + m.vertices[1]));  // on edge 0-1
    m.triangles.push_back({0, 8, 1});
    out.push_back({"zero_area", m, "triangle 12: degenerate (zero area"});

    m = cube();
    m.vertices.push_back(Vec3(0.5 * kSide, -kSide, -kSide));
    m.triangles.push_back({0, 1, 8});  // a fin on edge 0-1
    out.push_back({"fin", m, "triangle 1: non-manifold edge (1,0) shared by 3 triangles"});

    m = cube();
    m.vertices[6].y = std::nan("");
    out.push_back({"nan", m, "vertex 6: non-finite coordinate"});

    m = cube();
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
    out.push_back({"inside_out", m, "inside out: negative enclosed volume"});

    // Two cubes touching at one corner: every edge is fine, the vertex is not.
    m = cube();
    const TriMesh other = cube(kSide, Vec3(kSide));
    for (const Vec3& p : other.vertices) m.vertices.push_back(p);
    for (auto t : other.triangles) {
        for (auto& v : t) v = v == 0 ? 6 : v + 8;
        m.triangles.push_back(t);
    }
    out.push_back({"bowtie", m, "vertex 6: non-manifold vertex"});
    return out;
}

TEST(MeshValidate, EveryFaultIsReportedOnOneLine) {
    for (const Broken& b : broken_cubes()) {
        const std::string fault = validate_mesh(b.mesh);
        EXPECT_NE(fault.find(b.fault), std::string::npos) << b.name << ": " << fault;
        EXPECT_EQ(fault.find('\n'), std::string::npos) << fault;
    }
    TriMesh m = cube();
    m.triangles[4][2] = 99;
    EXPECT_NE(validate_mesh(m).find("triangle 4: vertex index 99 out of range (8 vertices)"), std::string::npos);
    EXPECT_NE(validate_mesh(TriMesh{}).find("empty"), std::string::npos);
    EXPECT_EQ(validate_mesh(cube()), "");
}

TEST_F(MeshFiles, BrokenObjNamesFileLineAndFault) {
    for (const Broken& b : broken_cubes()) {
        const std::string path = write(b.name + ".obj", obj_text(b.mesh));
        expect_error(load_mesh(path), path, b.fault);
    }
    // obj_text writes 2 header lines and 8 vertex lines, so triangle 5 is on line 16.
    TriMesh flipped = cube();
    std::swap(flipped.triangles[5][1], flipped.triangles[5][2]);
    const std::string path = write("flipped_line.obj", obj_text(flipped));
    expect_error(load_mesh(path), path, ": line 16: triangle 5: inconsistent orientation");

    TriMesh out_of_range = cube();
    out_of_range.triangles[4][2] = 99;
    const std::string p2 = write("out_of_range.obj", obj_text(out_of_range));
    expect_error(load_mesh(p2), p2, "line 15: vertex index 100 out of range (8 vertices)");
}

TEST_F(MeshFiles, BrokenOffIsReported) {
    for (const Broken& b : broken_cubes()) {
        const std::string path = write(b.name + ".off", off_text(b.mesh));
        expect_error(load_mesh(path), path, b.fault);
    }
    TriMesh out_of_range = cube();
    out_of_range.triangles[4][2] = 99;
    std::string path = write("out_of_range.off", off_text(out_of_range));
    expect_error(load_mesh(path), path, "vertex index 99 out of range (8 vertices)");
    std::string truncated = off_text(cube());
    truncated.resize(truncated.rfind('\n', truncated.size() - 2) + 1);  // drop the last face
    path = write("truncated.off", truncated);
    expect_error(load_mesh(path), path, "unexpected end of file: expected 12 faces, found 11");
}

// OpenMesh repairs or drops such faces on import; the loader must still report them.
TEST_F(MeshFiles, FaultsSurviveTheOpenMeshReaders) {
    struct Case {
        const char* fault_name;
        const char* fault;
    };
    const auto broken = broken_cubes();
    auto find = [&](const std::string& name) {
        return *std::find_if(broken.begin(), broken.end(), [&](const Broken& b) { return b.name == name; });
    };
    for (const Case c : {Case{"flipped", "inconsistent orientation"}, Case{"fin", "non-manifold edge"},
                         Case{"duplicate", "duplicate"}, Case{"open", "open boundary"},
                         Case{"inside_out", "inside out"}, Case{"bowtie", "non-manifold vertex"}}) {
        const TriMesh& m = find(c.fault_name).mesh;
        for (const auto& [ext, content] : std::vector<std::pair<std::string, std::string>>{
                 {"_ascii.stl", stl_ascii(m)}, {"_binary.stl", stl_binary(m)}, {".ply", ply_text(m, false)}}) {
            const std::string path = write(std::string(c.fault_name) + ext, content);
            expect_error(load_mesh(path), path, c.fault);
        }
    }
    // Faces OpenMesh refuses outright are counted.
    const TriMesh& repeated = find("repeated_vertex").mesh;
    std::string path = write("repeated_vertex.ply", ply_text(repeated, false));
    expect_error(load_mesh(path), path, "1 of 13 faces could not be added");
    path = write("repeated_vertex.stl", stl_binary(repeated));
    expect_error(load_mesh(path), path, "1 of 13 faces could not be added");

    std::string truncated = stl_binary(cube());
    truncated.resize(truncated.size() - 10);
    path = write("truncated.stl", truncated);
    expect_error(load_mesh(path), path, "binary STL header declares 12 triangles");
}

// ---- topology -----------------------------------------------------------------------------------

struct Counts {
    int flat = 0, convex = 0, concave = 0, mixed = 0;
};

Counts count_edges(const MeshTopology& t) {
    Counts c;
    for (const MeshEdge& e : t.edges) {
        c.flat += e.convexity == Convexity::Flat;
        c.convex += e.convexity == Convexity::Convex;
        c.concave += e.convexity == Convexity::Concave;
    }
    return c;
}

Counts count_vertices(const MeshTopology& t) {
    Counts c;
    for (Convexity v : t.vertex_convexity) {
        c.flat += v == Convexity::Flat;
        c.convex += v == Convexity::Convex;
        c.concave += v == Convexity::Concave;
        c.mixed += v == Convexity::Mixed;
    }
    return c;
}

// Structural invariants that hold for any closed mesh.
void expect_consistent(const TriMesh& m, const MeshTopology& t) {
    ASSERT_EQ(t.triangle_edges.size(), m.triangles.size());
    // Each triangle's byte of features says what its vertices' and edges' records say.
    ASSERT_EQ(t.triangle_corners.size(), m.triangles.size());
    for (size_t i = 0; i < m.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const Convexity cv = t.vertex_convexity[m.triangles[i][size_t(k)]];
            EXPECT_EQ((t.triangle_corners[i] >> k & 1u) != 0, cv == Convexity::Convex || cv == Convexity::Mixed)
                << "triangle " << i << " vertex " << k;
            EXPECT_EQ((t.triangle_corners[i] >> (3 + k) & 1u) != 0,
                      t.edges[t.triangle_edges[i][size_t(k)]].convexity == Convexity::Convex)
                << "triangle " << i << " edge " << k;
        }
    EXPECT_EQ(2 * t.edges.size(), 3 * m.triangles.size());
    for (size_t e = 0; e < t.edges.size(); ++e) {
        const MeshEdge& edge = t.edges[e];
        EXPECT_LT(edge.v[0], edge.v[1]);
        // tri[0] runs v0 -> v1, tri[1] runs v1 -> v0, and both list this edge.
        for (int side = 0; side < 2; ++side) {
            const auto& tri = m.triangles[edge.tri[side]];
            bool found = false;
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = side == 0 ? edge.v[0] : edge.v[1], b = side == 0 ? edge.v[1] : edge.v[0];
                if (tri[k] == a && tri[(k + 1) % 3] == b) {
                    found = true;
                    EXPECT_EQ(t.triangle_edges[edge.tri[side]][k], e);
                    EXPECT_EQ(t.triangle_neighbours[edge.tri[side]][k], edge.tri[1 - side]);
                }
            }
            EXPECT_TRUE(found) << "edge " << e << " side " << side;
        }
        EXPECT_EQ(edge.convexity == Convexity::Flat, edge.dihedral == 0.0);
        EXPECT_EQ(edge.convexity == Convexity::Convex, edge.dihedral > 0.0);
    }
    for (size_t i = 0; i < m.triangles.size(); ++i)
        EXPECT_NEAR(glm::length(t.triangle_normals[i]), 1.0, 1e-15);
    ASSERT_EQ(t.vertex_triangle_offsets.size(), m.vertices.size() + 1);
    ASSERT_EQ(t.vertex_edge_offsets.size(), m.vertices.size() + 1);
    EXPECT_EQ(t.vertex_triangle_offsets.back(), 3 * m.triangles.size());
    EXPECT_EQ(t.vertex_edge_offsets.back(), 2 * t.edges.size());
    for (size_t v = 0; v < m.vertices.size(); ++v) {
        for (uint32_t i = t.vertex_triangle_offsets[v]; i < t.vertex_triangle_offsets[v + 1]; ++i) {
            const auto& tri = m.triangles[t.vertex_triangles[i]];
            EXPECT_TRUE(tri[0] == v || tri[1] == v || tri[2] == v);
        }
        for (uint32_t i = t.vertex_edge_offsets[v]; i < t.vertex_edge_offsets[v + 1]; ++i) {
            const MeshEdge& e = t.edges[t.vertex_edges[i]];
            EXPECT_TRUE(e.v[0] == v || e.v[1] == v);
        }
    }
}

TEST(MeshTopology, CubeHasTwelveConvexEdgesAndSixFlatDiagonals) {
    const TriMesh m = cube();
    const MeshTopology t = build_topology(m);
    expect_consistent(m, t);
    ASSERT_EQ(t.edges.size(), 18u);
    const Counts e = count_edges(t);
    EXPECT_EQ(e.convex, 12);
    EXPECT_EQ(e.flat, 6);
    EXPECT_EQ(e.concave, 0);
    for (const MeshEdge& edge : t.edges)
        if (edge.convexity == Convexity::Convex) {
            EXPECT_NEAR(edge.dihedral, std::numbers::pi / 2, 1e-12);
        }
    EXPECT_EQ(count_vertices(t).convex, 8);
    // Normals point out of the cube: away from its centre.
    const Vec3 centre(kSide / 2);
    for (size_t i = 0; i < m.triangles.size(); ++i)
        EXPECT_GT(glm::dot(t.triangle_normals[i], m.vertices[m.triangles[i][0]] - centre), 0.0);
}

TEST(MeshTopology, LShapedPrismHasOneConcaveEdgeAtItsInnerCorner) {
    // L outline, counter-clockwise; vertex 3 = (1,1) is the reflex corner; caps are fans from it.
    const std::vector<glm::dvec2> poly = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    const TriMesh m = prism(poly, {{3, 4, 5}, {3, 5, 0}, {3, 0, 1}, {3, 1, 2}}, 1.0);
    ASSERT_EQ(validate_mesh(m), "");
    EXPECT_DOUBLE_EQ(mesh_volume(m), 3.0);
    const MeshTopology t = build_topology(m);
    expect_consistent(m, t);
    const Counts e = count_edges(t);
    EXPECT_EQ(e.concave, 1);
    EXPECT_EQ(e.convex, 17);
    EXPECT_EQ(e.flat, 12);
    for (const MeshEdge& edge : t.edges)
        if (edge.convexity == Convexity::Concave) {
            EXPECT_EQ(edge.v[0], 3u);
            EXPECT_EQ(edge.v[1], 9u);
            EXPECT_NEAR(edge.dihedral, -std::numbers::pi / 2, 1e-12);
        }
    const Counts v = count_vertices(t);
    EXPECT_EQ(v.mixed, 2);
    EXPECT_EQ(t.vertex_convexity[3], Convexity::Mixed);
    EXPECT_EQ(t.vertex_convexity[9], Convexity::Mixed);
    EXPECT_EQ(v.convex, 10);
}

TEST(MeshTopology, InwardCavityShellIsConcave) {
    TriMesh m = cube(2 * kSide);
    const TriMesh inner = cube(kSide, Vec3(kSide / 2));
    for (const Vec3& p : inner.vertices) m.vertices.push_back(p);
    for (const auto& t : inner.triangles) m.triangles.push_back({t[0] + 8, t[2] + 8, t[1] + 8});
    ASSERT_EQ(validate_mesh(m), "");
    EXPECT_DOUBLE_EQ(mesh_volume(m), 7 * kSide * kSide * kSide);
    const MeshTopology t = build_topology(m);
    expect_consistent(m, t);
    const Counts e = count_edges(t);
    EXPECT_EQ(e.convex, 12);
    EXPECT_EQ(e.concave, 12);
    EXPECT_EQ(e.flat, 12);
    for (const MeshEdge& edge : t.edges)
        if (edge.convexity == Convexity::Concave) {
            EXPECT_GE(edge.v[0], 8u);
        }
    for (uint32_t v = 0; v < 16; ++v)
        EXPECT_EQ(t.vertex_convexity[v], v < 8 ? Convexity::Convex : Convexity::Concave) << v;
}

TEST(MeshTopology, ResultDependsOnlyOnTheMesh) {
    const std::vector<glm::dvec2> poly = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    const TriMesh m = prism(poly, {{3, 4, 5}, {3, 5, 0}, {3, 0, 1}, {3, 1, 2}}, 1.0);
    const MeshTopology a = build_topology(m), b = build_topology(m);
    ASSERT_EQ(a.edges.size(), b.edges.size());
    for (size_t i = 0; i < a.edges.size(); ++i) {
        EXPECT_EQ(a.edges[i].v, b.edges[i].v);
        EXPECT_EQ(a.edges[i].tri, b.edges[i].tri);
        EXPECT_EQ(std::memcmp(&a.edges[i].dihedral, &b.edges[i].dihedral, sizeof(double)), 0);
    }
    // Edges come sorted by their vertex pair.
    for (size_t i = 1; i < a.edges.size(); ++i) EXPECT_LT(a.edges[i - 1].v, a.edges[i].v);
    EXPECT_EQ(a.vertex_triangles, b.vertex_triangles);
    EXPECT_EQ(a.vertex_edges, b.vertex_edges);
}

}  // namespace
}  // namespace sulcus
