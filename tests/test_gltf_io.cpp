// glTF export/import of content assets: a written asset reads back with float32-rounded vertices
// and poses, identical topology, materials and extras; the file also loads through the engine;
// mirrored and scaled node transforms from other tools keep solids outward; faults are one line
// naming the file; writes are whole or absent. Scan import scales by the file's unit.
#include "sulcus/content/asset.h"
#include "sulcus/content/gltf_io.h"
#include "sulcus/content/mesh_import.h"
#include "sulcus/content/primitives.h"
#include "sulcus/engine/mesh.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <unistd.h>

namespace sulcus {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

double f32(double v) { return double(float(v)); }

// A fresh folder per test, removed afterwards.
class GltfIo : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("sulcus_gltf_" + std::to_string(::getpid()) + "_" + std::string(info->name()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string file(const std::string& name) const { return (dir_ / name).string(); }
    fs::path dir_;
};

// The triangles [first, last) of `m` as a mesh of their own vertices (in order of first use).
TriMesh sub_mesh(const TriMesh& m, size_t first, size_t last) {
    TriMesh out;
    std::map<uint32_t, uint32_t> remap;
    for (size_t t = first; t < last; ++t) {
        std::array<uint32_t, 3> tri;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = m.triangles[t][size_t(k)];
            auto [it, added] = remap.emplace(v, uint32_t(out.vertices.size()));
            if (added) out.vertices.push_back(m.vertices[v]);
            tri[size_t(k)] = it->second;
        }
        out.triangles.push_back(tri);
    }
    return out;
}

TriMesh transformed(const TriMesh& m, const Pose& pose) {
    TriMesh out = m;
    for (Vec3& v : out.vertices) v = pose.apply(v);
    return out;
}

// Three nodes apart from one another: a box, a box split into two parts with two materials, and a
// rotated box; coordinates chosen so that float32 rounding changes them.
Asset test_asset() {
    Asset asset;
    asset.materials.push_back({"enamel", {0.95, 0.93, 0.88, 1.0}, 0.0, 0.31});
    asset.materials.push_back({"root", {0.9, 0.8, 0.6, 0.75}, 0.1, 0.62});

    AssetNode box;
    box.name = "box";
    box.parts.push_back({make_box(Vec3(0.0123456789, 0.0211111111, 0.0052345678), Vec3(0.0011, 0.0023, 0.0037)), 0});
    box.pose.position = Vec3(0.1234567891234, 0.0, -0.01);
    box.extras = {{"fdi", 36}, {"sites", {{"MB", {{"frame", {1.0, 2.5, -3.25e-7}}, {"depth_mm", 3.1}}}}}};
    asset.nodes.push_back(box);

    AssetNode split;
    split.name = "two parts";
    const TriMesh whole = make_box(Vec3(0.007, 0.0081, 0.0093));
    split.parts.push_back({sub_mesh(whole, 0, 4), 0});
    split.parts.push_back({sub_mesh(whole, 4, whole.triangles.size()), 1});
    split.pose.position = Vec3(-0.1, 0.05, 0.0333333333333);
    asset.nodes.push_back(split);

    AssetNode rotated;
    rotated.name = "rotated";
    rotated.parts.push_back({make_box(Vec3(0.005, 0.0061, 0.0072)), -1});
    rotated.pose.position = Vec3(0.0, 0.2, 0.3);
    rotated.pose.orientation = glm::angleAxis(0.7, glm::normalize(Vec3(1.0, 2.0, 3.0)));
    rotated.extras = {{"list", {1, "two", {{"three", 3.0}}, nullptr, true}},
                      {"big", 1234567890123456789LL},
                      {"tenth", 0.1},
                      {"unit", "\xC2\xB5m"}};
    asset.nodes.push_back(rotated);

    asset.extras = {{"format", "sulcus.test/1"},
                    {"chart", {{"teeth", {{"36", {{"pd_mm", {3.5, 2, 4.25}}, {"bop", false}}}}}}},
                    {"beyond_double", 9007199254740993ULL}};
    return asset;
}

TEST_F(GltfIo, RoundTripGivesBackFloat32RoundedMeshesPosesAndExactExtras) {
    const Asset in = test_asset();
    const std::string path = file("asset.glb");
    ASSERT_EQ(write_glb(in, path), "");
    const AssetLoad load = read_glb(path);
    ASSERT_TRUE(load.ok()) << load.error;
    const Asset& out = load.asset;

    EXPECT_EQ(out.materials, in.materials);
    EXPECT_EQ(out.extras, in.extras);
    EXPECT_EQ(out.extras.dump(), in.extras.dump());
    ASSERT_EQ(out.nodes.size(), in.nodes.size());
    for (size_t n = 0; n < in.nodes.size(); ++n) {
        SCOPED_TRACE("node " + std::to_string(n));
        const AssetNode &a = in.nodes[n], &b = out.nodes[n];
        EXPECT_EQ(b.name, a.name);
        EXPECT_EQ(b.extras, a.extras);
        EXPECT_EQ(b.extras.dump(), a.extras.dump());
        for (int k = 0; k < 3; ++k) EXPECT_EQ(b.pose.position[k], f32(a.pose.position[k]));
        const Quat& qa = a.pose.orientation;
        const Quat& qb = b.pose.orientation;
        EXPECT_NEAR(qb.w, f32(qa.w), 1e-7);
        EXPECT_NEAR(qb.x, f32(qa.x), 1e-7);
        EXPECT_NEAR(qb.y, f32(qa.y), 1e-7);
        EXPECT_NEAR(qb.z, f32(qa.z), 1e-7);
        EXPECT_NEAR(glm::length(qb), 1.0, 1e-15);
        ASSERT_EQ(b.parts.size(), a.parts.size());
        for (size_t p = 0; p < a.parts.size(); ++p) {
            const TriMesh &ma = a.parts[p].mesh, &mb = b.parts[p].mesh;
            EXPECT_EQ(b.parts[p].material, a.parts[p].material);
            EXPECT_EQ(mb.triangles, ma.triangles);  // same triangles, same order, same vertex sharing
            ASSERT_EQ(mb.vertices.size(), ma.vertices.size());
            for (size_t i = 0; i < ma.vertices.size(); ++i)
                for (int k = 0; k < 3; ++k) EXPECT_EQ(mb.vertices[i][k], f32(ma.vertices[i][k]));
        }
    }
    // The float32 rounding did change the input: the exact comparisons above are not trivial.
    EXPECT_NE(in.nodes[0].parts[0].mesh.vertices[0].x, out.nodes[0].parts[0].mesh.vertices[0].x);
}

TEST_F(GltfIo, AssetWithoutNodesKeepsItsExtras) {
    Asset in;
    in.extras = {{"format", "sulcus.chart/1"}, {"teeth", json::object()}};
    const std::string path = file("empty.glb");
    ASSERT_EQ(write_glb(in, path), "");
    const AssetLoad load = read_glb(path);
    ASSERT_TRUE(load.ok()) << load.error;
    EXPECT_TRUE(load.asset.nodes.empty());
    EXPECT_EQ(load.asset.extras.dump(), in.extras.dump());
}

TEST_F(GltfIo, FileHoldsUnitNormalsBoundsAndGenerator) {
    const std::string path = file("asset.glb");
    ASSERT_EQ(write_glb(test_asset(), path), "");
    tinygltf::TinyGLTF loader;
    tinygltf::Model model;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, path)) << err;
    EXPECT_EQ(model.asset.generator, "sulcus");
    EXPECT_EQ(model.asset.version, "2.0");
    ASSERT_EQ(model.meshes.size(), 3u);
    ASSERT_EQ(model.meshes[1].primitives.size(), 2u);
    for (const auto& mesh : model.meshes)
        for (const auto& prim : mesh.primitives) {
            const auto& pacc = model.accessors[size_t(prim.attributes.at("POSITION"))];
            const auto& nacc = model.accessors[size_t(prim.attributes.at("NORMAL"))];
            const auto& iacc = model.accessors[size_t(prim.indices)];
            EXPECT_EQ(pacc.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
            EXPECT_EQ(iacc.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
            ASSERT_EQ(pacc.minValues.size(), 3u);
            ASSERT_EQ(pacc.maxValues.size(), 3u);
            const auto& nbv = model.bufferViews[size_t(nacc.bufferView)];
            const auto& pbv = model.bufferViews[size_t(pacc.bufferView)];
            const unsigned char* nbase = model.buffers[0].data.data() + nbv.byteOffset + nacc.byteOffset;
            const unsigned char* pbase = model.buffers[0].data.data() + pbv.byteOffset + pacc.byteOffset;
            std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
            for (size_t i = 0; i < nacc.count; ++i) {
                float n[3], p[3];
                std::memcpy(n, nbase + 12 * i, 12);
                std::memcpy(p, pbase + 12 * i, 12);
                EXPECT_NEAR(std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]), 1.0, 1e-6);
                for (size_t k = 0; k < 3; ++k) {
                    lo[k] = std::min(lo[k], double(p[k]));
                    hi[k] = std::max(hi[k], double(p[k]));
                }
            }
            for (size_t k = 0; k < 3; ++k) {
                EXPECT_EQ(pacc.minValues[k], lo[k]);
                EXPECT_EQ(pacc.maxValues[k], hi[k]);
            }
        }
    // A box corner's area-weighted normal points diagonally out of the box.
    const auto& nacc = model.accessors[size_t(model.meshes[2].primitives[0].attributes.at("NORMAL"))];
    const auto& pacc = model.accessors[size_t(model.meshes[2].primitives[0].attributes.at("POSITION"))];
    const unsigned char* nb = model.buffers[0].data.data() + model.bufferViews[size_t(nacc.bufferView)].byteOffset;
    const unsigned char* pb = model.buffers[0].data.data() + model.bufferViews[size_t(pacc.bufferView)].byteOffset;
    for (size_t i = 0; i < pacc.count; ++i) {
        float n[3], p[3];
        std::memcpy(n, nb + 12 * i, 12);
        std::memcpy(p, pb + 12 * i, 12);
        EXPECT_GT(double(n[0]) * p[0] + double(n[1]) * p[1] + double(n[2]) * p[2], 0.0);  // box centred at 0
    }
}

TEST_F(GltfIo, MergedPartsBoundTheSolid) {
    const Asset asset = test_asset();
    const AssetNode& split = asset.nodes[1];
    const TriMesh merged = merged_parts(split);
    EXPECT_EQ(merged.vertices.size(), split.parts[0].mesh.vertices.size() + split.parts[1].mesh.vertices.size());
    EXPECT_EQ(merged.triangles.size(), 12u);
    EXPECT_NEAR(mesh_volume(merged), 8 * 0.007 * 0.0081 * 0.0093, 1e-15);
    // Vertices of the second part follow the first part's.
    EXPECT_EQ(merged.triangles[4][0], split.parts[1].mesh.triangles[0][0] + split.parts[0].mesh.vertices.size());
}

TEST_F(GltfIo, WrittenFileLoadsInTheEngineAsTheTransformedUnion) {
    const Asset in = test_asset();
    const std::string path = file("asset.glb");
    ASSERT_EQ(write_glb(in, path), "");
    const MeshLoad load = load_mesh(path);
    ASSERT_TRUE(load.ok()) << load.error;

    double volume = 0.0;
    size_t triangles = 0;
    std::vector<Vec3> expected;
    for (const AssetNode& node : read_glb(path).asset.nodes) {
        const TriMesh world = transformed(merged_parts(node), node.pose);
        volume += mesh_volume(world);
        triangles += world.triangles.size();
        expected.insert(expected.end(), world.vertices.begin(), world.vertices.end());
    }
    EXPECT_EQ(load.mesh.triangles.size(), triangles);
    EXPECT_NEAR(mesh_volume(load.mesh), volume, 1e-9 * volume);
    // Every engine vertex is one of the posed asset vertices (the engine welds the parts' copies).
    for (const Vec3& v : load.mesh.vertices) {
        double best = 1e300;
        for (const Vec3& e : expected) best = std::min(best, glm::length(v - e));
        EXPECT_LT(best, 1e-9);
    }

    // One closed node on its own validates as a solid in the engine.
    Asset single;
    single.nodes.push_back(in.nodes[2]);
    const std::string one = file("one.glb");
    ASSERT_EQ(write_glb(single, one), "");
    const MeshLoad l1 = load_mesh(one);
    ASSERT_TRUE(l1.ok()) << l1.error;
    EXPECT_EQ(validate_mesh(l1.mesh), "");
    EXPECT_NEAR(mesh_volume(l1.mesh), 8 * 0.005 * 0.0061 * 0.0072, 1e-6 * mesh_volume(l1.mesh));
}

// ---- files written by another tool ---------------------------------------------------------------

// A glTF model with one box mesh (float positions, uint32 indices) and no nodes yet.
tinygltf::Model box_model(const TriMesh& box, int mode = TINYGLTF_MODE_TRIANGLES) {
    tinygltf::Model model;
    model.asset.version = "2.0";
    tinygltf::Buffer buffer;
    for (const Vec3& v : box.vertices)
        for (int k = 0; k < 3; ++k) {
            const float f = float(v[k]);
            const auto* b = reinterpret_cast<const unsigned char*>(&f);
            buffer.data.insert(buffer.data.end(), b, b + 4);
        }
    const size_t index_offset = buffer.data.size();
    for (const auto& t : box.triangles)
        for (uint32_t i : t) {
            const auto* b = reinterpret_cast<const unsigned char*>(&i);
            buffer.data.insert(buffer.data.end(), b, b + 4);
        }
    model.buffers.push_back(buffer);
    tinygltf::BufferView pv, iv;
    pv.buffer = 0;
    pv.byteOffset = 0;
    pv.byteLength = index_offset;
    iv.buffer = 0;
    iv.byteOffset = index_offset;
    iv.byteLength = buffer.data.size() - index_offset;
    model.bufferViews = {pv, iv};
    tinygltf::Accessor pa, ia;
    pa.bufferView = 0;
    pa.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    pa.type = TINYGLTF_TYPE_VEC3;
    pa.count = box.vertices.size();
    ia.bufferView = 1;
    ia.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    ia.type = TINYGLTF_TYPE_SCALAR;
    ia.count = 3 * box.triangles.size();
    model.accessors = {pa, ia};
    tinygltf::Primitive prim;
    prim.attributes["POSITION"] = 0;
    prim.indices = 1;
    prim.mode = mode;
    tinygltf::Mesh mesh;
    mesh.name = "box";
    mesh.primitives.push_back(prim);
    model.meshes.push_back(mesh);
    model.scenes.push_back(tinygltf::Scene{});
    model.defaultScene = 0;
    return model;
}

void save(tinygltf::Model& model, const std::string& path) {
    tinygltf::TinyGLTF writer;
    ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, path, false, true, false, true)) << path;
}

TEST_F(GltfIo, MirroredAndScaledNodesKeepOutwardSolids) {
    const TriMesh box = make_box(Vec3(0.01, 0.02, 0.03), Vec3(0.001, 0.002, 0.003));
    const double box_volume = 8 * 0.01 * 0.02 * 0.03;
    tinygltf::Model model = box_model(box);

    // 0: mirrored in x, moved.  1: parent rotated about y, child 2 scaled (2, 1, -0.5) (mirrored, non-uniform).
    // 3: a mirroring 4x4 matrix with a shear.
    tinygltf::Node mirrored, parent, child, matrix;
    mirrored.name = "mirrored";
    mirrored.mesh = 0;
    mirrored.scale = {-1.0, 1.0, 1.0};
    mirrored.translation = {0.5, 0.0, 0.0};
    parent.name = "parent";
    parent.rotation = {0.0, std::sin(0.3), 0.0, std::cos(0.3)};
    parent.translation = {0.0, 0.5, 0.0};
    parent.children = {2};
    child.name = "scaled";
    child.mesh = 0;
    child.scale = {2.0, 1.0, -0.5};
    child.rotation = {std::sin(0.2), 0.0, 0.0, std::cos(0.2)};
    matrix.name = "sheared";
    matrix.mesh = 0;
    const glm::dmat4 m{{-1.0, 0.0, 0.0, 0.0}, {0.3, 1.0, 0.0, 0.0}, {0.0, 0.0, 1.5, 0.0}, {0.0, 0.0, 0.5, 1.0}};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) matrix.matrix.push_back(m[c][r]);
    model.nodes = {mirrored, parent, child, matrix};
    model.scenes[0].nodes = {0, 1, 3};
    const std::string path = file("mirrored.glb");
    save(model, path);

    const AssetLoad load = read_glb(path);
    ASSERT_TRUE(load.ok()) << load.error;
    ASSERT_EQ(load.asset.nodes.size(), 3u);

    // Expected world transforms, composed here as matrices.
    auto trs = [](const tinygltf::Node& n) {
        glm::dmat4 t(1.0), s(1.0), r(1.0);
        if (n.translation.size() == 3) t[3] = glm::dvec4(n.translation[0], n.translation[1], n.translation[2], 1.0);
        if (n.rotation.size() == 4)
            r = glm::mat4_cast(glm::normalize(Quat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2])));
        if (n.scale.size() == 3)
            for (int k = 0; k < 3; ++k) s[k][k] = n.scale[size_t(k)];
        return t * r * s;
    };
    const std::vector<std::pair<std::string, glm::dmat4>> expected = {
        {"mirrored", trs(mirrored)}, {"scaled", trs(parent) * trs(child)}, {"sheared", m}};
    for (size_t n = 0; n < expected.size(); ++n) {
        const AssetNode& node = load.asset.nodes[n];
        SCOPED_TRACE(node.name);
        EXPECT_EQ(node.name, expected[n].first);
        EXPECT_NEAR(glm::length(node.pose.orientation), 1.0, 1e-12);
        const TriMesh world = transformed(merged_parts(node), node.pose);
        const glm::dmat4& w = expected[n].second;
        ASSERT_EQ(world.vertices.size(), box.vertices.size());
        for (size_t i = 0; i < box.vertices.size(); ++i) {
            const Vec3 want = Vec3(w * glm::dvec4(f32(box.vertices[i].x), f32(box.vertices[i].y),
                                                  f32(box.vertices[i].z), 1.0));
            EXPECT_LT(glm::length(world.vertices[i] - want), 1e-12);
        }
        EXPECT_EQ(validate_mesh(world), "");
        const double det = std::fabs(glm::determinant(glm::dmat3(w)));
        EXPECT_NEAR(mesh_volume(world), det * box_volume, 1e-6 * det * box_volume);
        EXPECT_GT(mesh_volume(world), 0.0);
    }
    // The first node is mirrored: its winding was reversed relative to the file.
    EXPECT_EQ(load.asset.nodes[0].parts[0].mesh.triangles[0][1], box.triangles[0][2]);
}

TEST_F(GltfIo, TextGltfFromAnotherToolReadsWithRootExtras) {
    const TriMesh box = make_box(Vec3(0.01));
    tinygltf::Model model = box_model(box);
    tinygltf::Node node;
    node.mesh = 0;  // unnamed: takes its mesh's name
    node.extras = tinygltf::Value(tinygltf::Value::Object{{"fdi", tinygltf::Value(11)}});
    model.nodes = {node};
    model.scenes[0].nodes = {0};
    model.extras = tinygltf::Value(tinygltf::Value::Object{{"depth_mm", tinygltf::Value(2.5)}});
    const std::string path = file("text.gltf");
    tinygltf::TinyGLTF writer;
    ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, path, false, true, true, false));

    const AssetLoad load = read_glb(path);
    ASSERT_TRUE(load.ok()) << load.error;
    EXPECT_EQ(load.asset.extras, json({{"depth_mm", 2.5}}));
    ASSERT_EQ(load.asset.nodes.size(), 1u);
    EXPECT_EQ(load.asset.nodes[0].name, "box");
    EXPECT_EQ(load.asset.nodes[0].extras, json({{"fdi", 11}}));
    EXPECT_EQ(load.asset.nodes[0].parts[0].material, -1);
    EXPECT_EQ(load.asset.nodes[0].parts[0].mesh.triangles, box.triangles);
}

// ---- errors --------------------------------------------------------------------------------------

void expect_one_line_naming(const std::string& error, const std::string& path) {
    EXPECT_FALSE(error.empty());
    EXPECT_EQ(error.rfind(path + ": ", 0), 0u) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
}

TEST_F(GltfIo, MissingFileIsOneLineNamingIt) {
    const std::string path = file("absent.glb");
    const AssetLoad load = read_glb(path);
    expect_one_line_naming(load.error, path);
    EXPECT_NE(load.error.find("No such file"), std::string::npos) << load.error;
    EXPECT_TRUE(load.asset.nodes.empty());
}

TEST_F(GltfIo, TruncatedFileIsOneLineNamingIt) {
    const std::string good = file("good.glb");
    ASSERT_EQ(write_glb(test_asset(), good), "");
    std::ifstream in(good, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 100u);
    for (size_t keep : {bytes.size() / 2, bytes.size() - 4, size_t(30), size_t(3)}) {
        const std::string path = file("cut" + std::to_string(keep) + ".glb");
        std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(keep));
        const AssetLoad load = read_glb(path);
        SCOPED_TRACE(keep);
        expect_one_line_naming(load.error, path);
        const bool has_magic = keep >= 4;  // shorter files do not even start with "glTF"
        EXPECT_EQ(load.error.find("truncated") != std::string::npos, has_magic) << load.error;
        EXPECT_TRUE(load.asset.nodes.empty());
    }
}

TEST_F(GltfIo, NonTrianglePrimitiveIsNamed) {
    TriMesh box = make_box(Vec3(0.01));
    tinygltf::Model model = box_model(box, TINYGLTF_MODE_LINE);
    tinygltf::Node node;
    node.mesh = 0;
    model.nodes = {node};
    model.scenes[0].nodes = {0};
    const std::string path = file("lines.glb");
    save(model, path);
    const AssetLoad load = read_glb(path);
    expect_one_line_naming(load.error, path);
    EXPECT_NE(load.error.find("mesh 0 primitive 0: "), std::string::npos) << load.error;
    EXPECT_NE(load.error.find("triangles only"), std::string::npos) << load.error;
}

TEST_F(GltfIo, WriteIsWholeOrAbsent) {
    // Into a folder that does not exist: an error, and no folder, file or temporary appears.
    const fs::path missing = dir_ / "missing";
    const std::string path = (missing / "a.glb").string();
    expect_one_line_naming(write_glb(test_asset(), path), path);
    EXPECT_FALSE(fs::exists(missing));

    // A refused asset leaves an existing file as it was, with no temporary beside it.
    const std::string existing = file("existing.glb");
    std::ofstream(existing) << "old";
    Asset bad = test_asset();
    bad.nodes[1].parts[1].material = 7;
    const std::string error = write_glb(bad, existing);
    expect_one_line_naming(error, existing);
    EXPECT_NE(error.find("node 1 'two parts': part 1: material 7 does not exist"), std::string::npos) << error;
    std::ifstream kept(existing);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(kept), std::istreambuf_iterator<char>()), "old");
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);

    // A good write replaces it whole and leaves no temporary.
    ASSERT_EQ(write_glb(test_asset(), existing), "");
    EXPECT_TRUE(read_glb(existing).ok());
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

// ---- scan import ---------------------------------------------------------------------------------

TEST_F(GltfIo, ImportScalesMillimetresToMetres) {
    const TriMesh mm = make_box(Vec3(5.0, 6.5, 7.25), Vec3(1.0, -2.0, 3.3));  // a 10 x 13 x 14.5 mm block
    const std::string path = file("block.obj");
    std::string error;
    ASSERT_TRUE(write_obj(mm, path, &error)) << error;

    const ImportResult r = import_mesh(path, LengthUnit::Millimetre);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_EQ(r.warning, "");
    EXPECT_EQ(r.mesh.triangles, mm.triangles);
    ASSERT_EQ(r.mesh.vertices.size(), mm.vertices.size());
    for (size_t i = 0; i < mm.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(r.mesh.vertices[i][k], mm.vertices[i][k] * 1e-3);

    const ImportResult in_inch = import_mesh(path, LengthUnit::Inch);
    ASSERT_TRUE(in_inch.ok());
    EXPECT_DOUBLE_EQ(in_inch.mesh.vertices[0].x, mm.vertices[0].x * 0.0254);
}

TEST_F(GltfIo, ImportWarnsOfImplausibleSize) {
    const std::string path = file("scan.obj");
    std::string error;
    ASSERT_TRUE(write_obj(make_box(Vec3(17.5, 3.0, 2.0)), path, &error)) << error;  // 35 units wide

    const ImportResult as_m = import_mesh(path, LengthUnit::Metre);
    ASSERT_TRUE(as_m.ok()) << as_m.error;
    EXPECT_EQ(as_m.warning, path + ": size 35 m after scaling from m: wrong unit?");

    const ImportResult as_um = import_mesh(path, LengthUnit::Micrometre);
    ASSERT_TRUE(as_um.ok());
    EXPECT_EQ(as_um.warning, path + ": size 35 um after scaling from um: wrong unit?");

    const ImportResult as_mm = import_mesh(path, LengthUnit::Millimetre);
    ASSERT_TRUE(as_mm.ok());
    EXPECT_EQ(as_mm.warning, "");
}

TEST_F(GltfIo, ImportKeepsTheEnginesErrorForOpenScans) {
    TriMesh open = make_box(Vec3(5.0));
    open.triangles.pop_back();
    const std::string path = file("open.obj");
    std::string error;
    ASSERT_TRUE(write_obj(open, path, &error)) << error;
    const ImportResult r = import_mesh(path, LengthUnit::Millimetre);
    EXPECT_FALSE(r.ok());
    EXPECT_EQ(r.error, load_mesh(path).error);
    expect_one_line_naming(r.error, path);
    EXPECT_TRUE(r.mesh.vertices.empty());
}

TEST(LengthUnits, ParseAndScale) {
    const std::vector<std::pair<std::string, LengthUnit>> names = {{"m", LengthUnit::Metre},
                                                                   {"cm", LengthUnit::Centimetre},
                                                                   {"mm", LengthUnit::Millimetre},
                                                                   {"um", LengthUnit::Micrometre},
                                                                   {"\xC2\xB5m", LengthUnit::Micrometre},
                                                                   {"in", LengthUnit::Inch}};
    for (const auto& [name, unit] : names) {
        LengthUnit u = unit == LengthUnit::Metre ? LengthUnit::Inch : LengthUnit::Metre;
        EXPECT_TRUE(parse_length_unit(name, &u)) << name;
        EXPECT_EQ(u, unit) << name;
    }
    for (const std::string bad : {"", "M", "MM", "km", "mm ", "inch", "nm"}) {
        LengthUnit u = LengthUnit::Centimetre;
        EXPECT_FALSE(parse_length_unit(bad, &u)) << bad;
        EXPECT_EQ(u, LengthUnit::Centimetre);
    }
    EXPECT_EQ(metres_per(LengthUnit::Metre), 1.0);
    EXPECT_EQ(metres_per(LengthUnit::Centimetre), 0.01);
    EXPECT_EQ(metres_per(LengthUnit::Millimetre), 0.001);
    EXPECT_EQ(metres_per(LengthUnit::Micrometre), 1e-6);
    EXPECT_EQ(metres_per(LengthUnit::Inch), 0.0254);
    for (const auto& [name, unit] : names)
        if (name != "\xC2\xB5m") {
            EXPECT_EQ(length_unit_name(unit), name);
        }
}

}  // namespace
}  // namespace sulcus
