// glTF 2.0 output and input of content assets.
//
// The writer builds the JSON with nlohmann-json and the GLB container itself: tinygltf's Value
// holds integers as 32-bit int, which would alter 64-bit integers in extras; nlohmann keeps every
// JSON number as written. The reader uses tinygltf (so files from other tools are accepted as
// tinygltf accepts them), taking extras from the original JSON text tinygltf keeps on request.
#include "sulcus/content/gltf_io.h"

#include <glm/gtc/quaternion.hpp>
#include <tiny_gltf.h>

#include "sulcus/engine/gltf_primitive.h"

#include <bit>
#include <cctype>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace sulcus {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

static_assert(std::endian::native == std::endian::little, "GLB is little-endian; buffers are copied as they are");

constexpr uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
constexpr int kComponentFloat = 5126;
constexpr int kComponentUint = 5125;
constexpr int kTargetArrayBuffer = 34962;
constexpr int kTargetElementArrayBuffer = 34963;
constexpr int kModeTriangles = 4;

std::string one_line(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '\n') out += "; ";
        else if (static_cast<unsigned char>(c) < 32 || c == 127) out += ' ';
        else out += c;
    }
    while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
    return out;
}

std::string quoted(const std::string& name) { return "'" + one_line(name) + "'"; }

bool fits_float(double v) { return std::isfinite(v) && std::fabs(v) <= double(FLT_MAX); }

double f32(double v) { return double(float(v)); }

// ---- writing -----------------------------------------------------------------------------------

// Unit vertex normals weighted by the area of the incident triangles (the cross product's length
// is twice the area, so summing unnormalised cross products weights by area).
std::vector<Vec3> vertex_normals(const TriMesh& mesh) {
    std::vector<Vec3> normals(mesh.vertices.size(), Vec3(0.0));
    for (const auto& t : mesh.triangles) {
        const Vec3& a = mesh.vertices[t[0]];
        const Vec3 n = glm::cross(mesh.vertices[t[1]] - a, mesh.vertices[t[2]] - a);
        for (uint32_t v : t) normals[v] += n;
    }
    for (Vec3& n : normals) {
        const double len = glm::length(n);
        // Unused vertices and points where the faces cancel still need a unit normal.
        n = (len > 0.0 && std::isfinite(len)) ? n / len : Vec3(0.0, 1.0, 0.0);
    }
    return normals;
}

// The binary chunk: accessor data back to back, each start aligned to 4 bytes.
struct BinaryBuffer {
    std::string bytes;
    size_t add(const void* data, size_t size) {
        while (bytes.size() % 4 != 0) bytes.push_back('\0');
        const size_t offset = bytes.size();
        bytes.append(static_cast<const char*>(data), size);
        return offset;
    }
};

// Appends a buffer view and an accessor over `data`; returns the accessor index.
int add_accessor(json& gltf, BinaryBuffer& bin, const void* data, size_t bytes, size_t count, int component,
                 const char* type, int target) {
    const size_t offset = bin.add(data, bytes);
    json& views = gltf["bufferViews"];
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", target}});
    json& accessors = gltf["accessors"];
    accessors.push_back(
        {{"bufferView", views.size() - 1}, {"componentType", component}, {"count", count}, {"type", type}});
    return int(accessors.size() - 1);
}

// Checks a part before anything is written; returns "" or what is wrong.
std::string check_part(const MeshPart& part, size_t materials) {
    const TriMesh& m = part.mesh;
    if (m.vertices.empty() || m.triangles.empty()) return "empty mesh (glTF has no empty primitives)";
    if (m.vertices.size() > UINT32_MAX) return "too many vertices";
    for (size_t i = 0; i < m.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k)
            if (!fits_float(m.vertices[i][k]))
                return "vertex " + std::to_string(i) + ": coordinate not finite or out of float32 range";
    for (size_t i = 0; i < m.triangles.size(); ++i)
        for (uint32_t v : m.triangles[i])
            if (v >= m.vertices.size())
                return "triangle " + std::to_string(i) + ": vertex index " + std::to_string(v) + " out of range";
    if (part.material < -1 || (part.material >= 0 && size_t(part.material) >= materials))
        return "material " + std::to_string(part.material) + " does not exist";
    return "";
}

std::string check_material(const Material& m) {
    for (double c : m.base_color)
        if (!(c >= 0.0 && c <= 1.0)) return "base colour components must lie in [0, 1]";
    if (!(m.metallic >= 0.0 && m.metallic <= 1.0)) return "metallic must lie in [0, 1]";
    if (!(m.roughness >= 0.0 && m.roughness <= 1.0)) return "roughness must lie in [0, 1]";
    return "";
}

bool has_extras(const json& extras) { return !(extras.is_null() || (extras.is_object() && extras.empty())); }

// Builds the glTF JSON and the binary chunk; returns "" or what is wrong.
std::string build_gltf(const Asset& asset, json& gltf, BinaryBuffer& bin) {
    gltf = json::object();
    gltf["asset"] = {{"version", "2.0"}, {"generator", "sulcus"}};

    for (size_t i = 0; i < asset.materials.size(); ++i) {
        const Material& m = asset.materials[i];
        if (const std::string e = check_material(m); !e.empty())
            return "material " + std::to_string(i) + " " + quoted(m.name) + ": " + e;
        json pbr = {{"baseColorFactor", m.base_color}, {"metallicFactor", m.metallic}, {"roughnessFactor", m.roughness}};
        json jm = {{"pbrMetallicRoughness", pbr}};
        if (!m.name.empty()) jm["name"] = m.name;
        gltf["materials"].push_back(std::move(jm));
    }

    json scene = json::object();
    for (size_t n = 0; n < asset.nodes.size(); ++n) {
        const AssetNode& node = asset.nodes[n];
        const std::string place = "node " + std::to_string(n) + " " + quoted(node.name) + ": ";
        // A node without a mesh would not be read back as an AssetNode.
        if (node.parts.empty()) return place + "no mesh parts";
        const Pose& pose = node.pose;
        const Quat& q = pose.orientation;
        for (int k = 0; k < 3; ++k)
            if (!fits_float(pose.position[k])) return place + "pose position not finite or out of float32 range";
        const double norm2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
        if (!(std::fabs(norm2 - 1.0) <= 1e-6)) return place + "pose orientation is not a unit quaternion";

        json mesh = {{"primitives", json::array()}};
        if (!node.name.empty()) mesh["name"] = node.name;
        for (size_t p = 0; p < node.parts.size(); ++p) {
            const MeshPart& part = node.parts[p];
            if (const std::string e = check_part(part, asset.materials.size()); !e.empty())
                return place + "part " + std::to_string(p) + ": " + e;
            const TriMesh& m = part.mesh;
            std::vector<float> positions, normals;
            positions.reserve(3 * m.vertices.size());
            normals.reserve(3 * m.vertices.size());
            std::array<float, 3> lo{FLT_MAX, FLT_MAX, FLT_MAX}, hi{-FLT_MAX, -FLT_MAX, -FLT_MAX};
            for (const Vec3& v : m.vertices)
                for (int k = 0; k < 3; ++k) {
                    const float f = float(v[k]);
                    positions.push_back(f);
                    lo[size_t(k)] = std::min(lo[size_t(k)], f);
                    hi[size_t(k)] = std::max(hi[size_t(k)], f);
                }
            for (const Vec3& nrm : vertex_normals(m))
                for (int k = 0; k < 3; ++k) normals.push_back(float(nrm[k]));
            std::vector<uint32_t> indices;
            indices.reserve(3 * m.triangles.size());
            for (const auto& t : m.triangles) indices.insert(indices.end(), t.begin(), t.end());

            const int pos = add_accessor(gltf, bin, positions.data(), positions.size() * sizeof(float),
                                         m.vertices.size(), kComponentFloat, "VEC3", kTargetArrayBuffer);
            gltf["accessors"][size_t(pos)]["min"] = {double(lo[0]), double(lo[1]), double(lo[2])};
            gltf["accessors"][size_t(pos)]["max"] = {double(hi[0]), double(hi[1]), double(hi[2])};
            const int nrm = add_accessor(gltf, bin, normals.data(), normals.size() * sizeof(float), m.vertices.size(),
                                         kComponentFloat, "VEC3", kTargetArrayBuffer);
            const int idx = add_accessor(gltf, bin, indices.data(), indices.size() * sizeof(uint32_t), indices.size(),
                                         kComponentUint, "SCALAR", kTargetElementArrayBuffer);
            json prim = {{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}}, {"indices", idx}, {"mode", kModeTriangles}};
            if (part.material >= 0) prim["material"] = part.material;
            mesh["primitives"].push_back(std::move(prim));
        }
        gltf["meshes"].push_back(std::move(mesh));

        json jn = {{"mesh", n},
                   {"translation", {f32(pose.position.x), f32(pose.position.y), f32(pose.position.z)}},
                   {"rotation", {f32(q.x), f32(q.y), f32(q.z), f32(q.w)}}};  // glTF order x, y, z, w
        if (!node.name.empty()) jn["name"] = node.name;
        if (has_extras(node.extras)) jn["extras"] = node.extras;
        gltf["nodes"].push_back(std::move(jn));
        scene["nodes"].push_back(n);
    }
    if (has_extras(asset.extras)) scene["extras"] = asset.extras;
    gltf["scenes"] = json::array({scene});
    gltf["scene"] = 0;
    if (!bin.bytes.empty()) gltf["buffers"] = json::array({{{"byteLength", bin.bytes.size()}}});
    return "";
}

void append_u32(std::string& out, uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); }

std::string glb_container(std::string text, std::string bin) {
    while (text.size() % 4 != 0) text.push_back(' ');   // the JSON chunk pads with spaces
    while (bin.size() % 4 != 0) bin.push_back('\0');     // the binary chunk with zeros
    const size_t total = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size());
    std::string out;
    out.reserve(total);
    append_u32(out, kGlbMagic);
    append_u32(out, 2);
    append_u32(out, uint32_t(total));
    append_u32(out, uint32_t(text.size()));
    append_u32(out, kChunkJson);
    out += text;
    if (!bin.empty()) {
        append_u32(out, uint32_t(bin.size()));
        append_u32(out, kChunkBin);
        out += bin;
    }
    return out;
}

// ---- reading -----------------------------------------------------------------------------------

bool read_whole_file(const std::string& path, std::string& data, std::string& error) {
    std::error_code ec;
    if (!fs::exists(path, ec)) {
        error = "cannot open: No such file or directory";
        return false;
    }
    if (!fs::is_regular_file(path, ec)) {
        error = "cannot open: not a regular file";
        return false;
    }
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) {
        error = std::string("cannot open: ") + std::strerror(errno);
        return false;
    }
    char buf[1 << 16];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.append(buf, n);
    const bool failed = std::ferror(f);
    std::fclose(f);
    if (failed) error = "read error";
    return !failed;
}

// Images do not matter here: accept them undecoded.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
    return true;
}

// A node's world transform. `rigid` while every transform on the path is a rotation and a
// translation given as such; then `pose` is exact and the vertices stay as stored.
struct Transform {
    bool rigid = true;
    Pose pose;
    glm::dmat4 matrix{1.0};
};

bool local_transform(const tinygltf::Node& node, Transform& out, std::string& error) {
    out = Transform{};
    if (node.matrix.size() == 16) {
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) out.matrix[c][r] = node.matrix[size_t(4 * c + r)];
        out.rigid = false;  // decomposed exactly later, whatever it holds
        for (double v : node.matrix)
            if (!std::isfinite(v)) {
                error = "matrix not finite";
                return false;
            }
        return true;
    }
    if (node.translation.size() == 3)
        out.pose.position = Vec3(node.translation[0], node.translation[1], node.translation[2]);
    if (node.rotation.size() == 4) {
        const Quat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
        const double len = glm::length(q);
        if (!(len > 0.0) || !std::isfinite(len)) {
            error = "rotation is not a quaternion";
            return false;
        }
        out.pose.orientation = q / len;  // float32 rounding leaves it slightly off unit length
    }
    Vec3 scale(1.0);
    if (node.scale.size() == 3) scale = Vec3(node.scale[0], node.scale[1], node.scale[2]);
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(out.pose.position[k]) || !std::isfinite(scale[k])) {
            error = "translation or scale not finite";
            return false;
        }
    out.rigid = scale == Vec3(1.0);
    glm::dmat4 t(1.0), s(1.0);
    t[3] = glm::dvec4(out.pose.position, 1.0);
    for (int k = 0; k < 3; ++k) s[k][k] = scale[k];
    out.matrix = t * glm::mat4_cast(out.pose.orientation) * s;
    return true;
}

Transform compose(const Transform& parent, const Transform& local) {
    Transform out;
    out.rigid = parent.rigid && local.rigid;
    out.pose.position = parent.pose.apply(local.pose.position);
    out.pose.orientation = glm::normalize(parent.pose.orientation * local.pose.orientation);
    out.matrix = parent.matrix * local.matrix;
    return out;
}

// Splits A = R S with R a proper rotation (from the polar decomposition, so S is a pure stretch
// when det A > 0, and a stretch with a point reflection when det A < 0).
bool rotation_and_rest(const glm::dmat3& a, glm::dmat3& r, glm::dmat3& s) {
    const double det = glm::determinant(a);
    if (!std::isfinite(det) || std::fabs(det) < 1e-300) return false;
    glm::dmat3 x = a;
    for (int it = 0; it < 100; ++it) {
        const glm::dmat3 next = 0.5 * (x + glm::transpose(glm::inverse(x)));
        double change = 0.0;
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) change = std::max(change, std::fabs(next[c][k] - x[c][k]));
        x = next;
        if (change < 1e-15) break;
    }
    r = det < 0.0 ? -x : x;
    s = glm::transpose(r) * a;
    return true;
}

// One primitive as a part: vertices through `linear` (when baking), winding reversed if mirrored.
bool read_primitive(const tinygltf::Model& model, const tinygltf::Primitive& prim, const glm::dmat3* linear,
                    MeshPart& part, std::string& error) {
    if (!append_gltf_triangles(model, prim, linear ? glm::dmat4(*linear) : glm::dmat4(1.0), part.mesh, error))
        return false;
    if (prim.material >= 0 && size_t(prim.material) >= model.materials.size()) {
        error = "material " + std::to_string(prim.material) + " does not exist";
        return false;
    }
    part.material = prim.material;
    return true;
}

bool parse_extras(const std::string& text, json& out, std::string& error) {
    if (text.empty()) {
        out = json::object();
        return true;
    }
    try {
        out = json::parse(text);
    } catch (const std::exception& e) {
        error = std::string("extras: ") + e.what();
        return false;
    }
    return true;
}

Material read_material(const tinygltf::Material& m) {
    Material out;
    out.name = m.name;
    const auto& pbr = m.pbrMetallicRoughness;
    if (pbr.baseColorFactor.size() == 4)
        for (size_t k = 0; k < 4; ++k) out.base_color[k] = pbr.baseColorFactor[k];
    out.metallic = pbr.metallicFactor;
    out.roughness = pbr.roughnessFactor;
    return out;
}

// Fills `asset` from a parsed model; returns "" or "place: what".
std::string read_model(const tinygltf::Model& model, Asset& asset) {
    for (const auto& m : model.materials) asset.materials.push_back(read_material(m));

    // Roots: the default scene's nodes, else every node that is no other node's child.
    std::vector<int> roots;
    const tinygltf::Scene* scene = nullptr;
    if (!model.scenes.empty()) {
        const size_t s = model.defaultScene >= 0 && size_t(model.defaultScene) < model.scenes.size()
                             ? size_t(model.defaultScene)
                             : 0;
        scene = &model.scenes[s];
        roots = scene->nodes;
    } else {
        std::vector<bool> is_child(model.nodes.size(), false);
        for (const auto& node : model.nodes)
            for (int c : node.children)
                if (c >= 0 && size_t(c) < model.nodes.size()) is_child[size_t(c)] = true;
        for (size_t i = 0; i < model.nodes.size(); ++i)
            if (!is_child[i]) roots.push_back(int(i));
    }
    std::string error;
    const std::string& extras_text =
        scene && !scene->extras_json_string.empty() ? scene->extras_json_string : model.extras_json_string;
    if (!parse_extras(extras_text, asset.extras, error)) return (scene ? "scene: " : "") + error;

    std::vector<bool> visited(model.nodes.size(), false);
    std::vector<std::pair<int, Transform>> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, Transform{}});
    while (!stack.empty()) {
        const auto [index, parent] = stack.back();
        stack.pop_back();
        const std::string place = "node " + std::to_string(index) + ": ";
        if (index < 0 || size_t(index) >= model.nodes.size()) return place + "does not exist";
        if (visited[size_t(index)]) return place + "reached twice (the node graph is not a tree)";
        visited[size_t(index)] = true;
        const tinygltf::Node& node = model.nodes[size_t(index)];
        Transform local;
        if (!local_transform(node, local, error)) return place + error;
        const Transform world = compose(parent, local);
        if (node.mesh >= 0) {
            if (size_t(node.mesh) >= model.meshes.size())
                return place + "mesh " + std::to_string(node.mesh) + " does not exist";
            const tinygltf::Mesh& mesh = model.meshes[size_t(node.mesh)];
            AssetNode out;
            out.name = node.name.empty() ? mesh.name : node.name;
            if (!parse_extras(node.extras_json_string, out.extras, error)) return place + error;
            glm::dmat3 rest(1.0);
            const bool bake = !world.rigid;
            if (world.rigid) {
                out.pose = world.pose;
            } else {
                glm::dmat3 r;
                if (!rotation_and_rest(glm::dmat3(world.matrix), r, rest)) return place + "singular transform";
                out.pose.orientation = glm::normalize(glm::quat_cast(r));
                out.pose.position = Vec3(world.matrix[3]);
            }
            for (size_t p = 0; p < mesh.primitives.size(); ++p) {
                MeshPart part;
                if (!read_primitive(model, mesh.primitives[p], bake ? &rest : nullptr, part, error))
                    return "mesh " + std::to_string(node.mesh) + " primitive " + std::to_string(p) + ": " + error;
                out.parts.push_back(std::move(part));
            }
            asset.nodes.push_back(std::move(out));
        }
        for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.push_back({*it, world});
    }
    return "";
}

}  // namespace

std::string write_glb(const Asset& asset, const std::string& path) {
    auto fail = [&](const std::string& what) { return one_line(path + ": " + what); };
    json gltf;
    BinaryBuffer bin;
    std::string text;
    try {
        if (const std::string e = build_gltf(asset, gltf, bin); !e.empty()) return fail(e);
        text = gltf.dump();  // strict: a name or string in extras that is not UTF-8 throws
    } catch (const std::exception& e) {
        return fail(std::string("cannot encode: ") + e.what());
    }
    if (text.size() + bin.bytes.size() > UINT32_MAX - 64) return fail("asset too large for one GLB file");
    const std::string out = glb_container(std::move(text), std::move(bin.bytes));

    const std::string tmp = path + ".tmp";
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) return fail(std::string("cannot write: ") + std::strerror(errno));
    const bool written = std::fwrite(out.data(), 1, out.size(), f) == out.size();
    const bool closed = std::fclose(f) == 0;
    if (!written || !closed) {
        std::remove(tmp.c_str());
        return fail("write error");
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        std::remove(tmp.c_str());
        return fail("cannot rename temporary file: " + ec.message());
    }
    return "";
}

AssetLoad read_glb(const std::string& path) {
    AssetLoad result;
    auto fail = [&](const std::string& what) {
        result.asset = Asset{};
        result.error = one_line(path + ": " + what);
        return result;
    };
    std::string data, error;
    if (!read_whole_file(path, data, error)) return fail(error);
    if (data.empty()) return fail("empty file");
    if (data.size() > UINT32_MAX) return fail("file too large");

    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    const bool binary = data.compare(0, 4, "glTF") == 0;
    if (ext == ".glb" && !binary) return fail("not a binary glTF file (no 'glTF' header)");
    if (binary) {
        // tinygltf only says "Invalid glTF binary" for a cut file: say what is wrong.
        uint32_t header[3] = {0, 0, 0};
        if (data.size() < sizeof header) return fail("truncated: shorter than the 12-byte GLB header");
        std::memcpy(header, data.data(), sizeof header);
        if (header[1] != 2) return fail("GLB version " + std::to_string(header[1]) + " is not supported (2 only)");
        if (header[2] > data.size())
            return fail("truncated: the GLB header declares " + std::to_string(header[2]) + " bytes, the file has " +
                        std::to_string(data.size()));
    }

    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    loader.SetStoreOriginalJSONForExtrasAndExtensions(true);
    tinygltf::Model model;
    std::string err, warn;
    const std::string base_dir = fs::path(path).parent_path().string();
    try {
        const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                                             reinterpret_cast<const unsigned char*>(data.data()),
                                                             unsigned(data.size()), base_dir)
                               : loader.LoadASCIIFromString(&model, &err, &warn, data.data(), unsigned(data.size()),
                                                            base_dir);
        if (!ok) return fail(err.empty() ? "not a readable glTF file" : err);
        if (const std::string e = read_model(model, result.asset); !e.empty()) return fail(e);
    } catch (const std::exception& e) {
        return fail(std::string("read error: ") + e.what());
    }
    return result;
}

}  // namespace sulcus
