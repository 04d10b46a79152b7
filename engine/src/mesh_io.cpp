// Mesh files: OBJ and OFF by strict readers of our own (so that a flipped, duplicate or
// non-manifold face reaches validation instead of being repaired on the way in), PLY and STL by
// OpenMesh with a check that no face was dropped or detached, glTF/GLB by tinygltf; and OBJ
// output written whole or not at all.
#include "mesh_fault.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <glm/gtc/quaternion.hpp>
#include <tiny_gltf.h>

#include "sulcus/engine/gltf_primitive.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <numeric>
#include <string_view>

namespace sulcus {
namespace {

namespace fs = std::filesystem;

// What a reader produces: the mesh, and for each triangle (and vertex) where it came from in
// the file, so that a validation fault can name the place.
struct RawMesh {
    TriMesh mesh;
    std::vector<uint64_t> triangle_source;  // line or face number per triangle (may be empty)
    std::vector<uint64_t> vertex_source;    // line number per vertex (may be empty)
    const char* triangle_place = "";        // "line", "face", "facet"
    const char* vertex_place = "";
    std::string error;                      // "place: what", without the path
};

// Keeps file text out of messages from breaking the one-line rule.
std::string printable(std::string_view s, size_t max_len = 40) {
    std::string out;
    for (char c : s.substr(0, max_len)) out += (static_cast<unsigned char>(c) < 32 || c == 127) ? '?' : c;
    if (s.size() > max_len) out += "...";
    return out;
}

std::string one_line(std::string s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
    std::string out;
    for (char c : s) {
        if (c == '\n') out += "; ";
        else if (static_cast<unsigned char>(c) < 32 || c == 127) out += ' ';
        else out += c;
    }
    return out;
}

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
    data.clear();
    char buf[1 << 16];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.append(buf, n);
    const bool failed = std::ferror(f);
    std::fclose(f);
    if (failed) {
        error = "read error";
        return false;
    }
    return true;
}

// ---- text helpers ------------------------------------------------------------------------------

// Splits text into lines (\n, \r\n) with '#' comments removed; numbers are 1-based.
struct Line {
    uint64_t number;
    std::vector<std::string_view> tokens;
};

// Whitespace of the C locale, without a locale look-up per character.
bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

std::vector<std::string_view> split_tokens(std::string_view s) {
    std::vector<std::string_view> out;
    size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && is_space(s[i])) ++i;
        size_t j = i;
        while (j < s.size() && !is_space(s[j])) ++j;
        if (j > i) out.push_back(s.substr(i, j - i));
        i = j;
    }
    return out;
}

std::vector<Line> content_lines(std::string_view text) {
    std::vector<Line> lines;
    uint64_t number = 0;
    size_t pos = text.starts_with("\xEF\xBB\xBF") ? 3 : 0;  // UTF-8 byte order mark
    while (pos < text.size()) {
        size_t end = text.find('\n', pos);
        if (end == std::string_view::npos) end = text.size();
        std::string_view line = text.substr(pos, end - pos);
        pos = end + 1;
        ++number;
        const size_t hash = line.find('#');
        if (hash != std::string_view::npos) line = line.substr(0, hash);
        auto tokens = split_tokens(line);
        if (!tokens.empty()) lines.push_back({number, std::move(tokens)});
    }
    return lines;
}

bool parse_double(std::string_view s, double& out) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && ptr == s.data() + s.size();
}

bool parse_int(std::string_view s, int64_t& out) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && ptr == s.data() + s.size();
}

std::string at_line(uint64_t line, const std::string& what) { return "line " + std::to_string(line) + ": " + what; }

// Splits a polygon into a fan of triangles around its first corner.
void add_polygon(RawMesh& raw, const std::vector<uint32_t>& poly, uint64_t source) {
    for (size_t i = 1; i + 1 < poly.size(); ++i) {
        raw.mesh.triangles.push_back({poly[0], poly[i], poly[i + 1]});
        raw.triangle_source.push_back(source);
    }
}

// ---- OBJ ---------------------------------------------------------------------------------------

bool obj_ignored_statement(std::string_view k) {
    static constexpr std::string_view ignored[] = {
        "vn",   "vt",   "vp",      "g",        "o",        "s",        "usemtl",   "mtllib", "l",    "p",
        "cstype", "deg", "bmat",   "step",     "curv",     "curv2",    "surf",     "parm",   "trim", "hole",
        "scrv", "sp",   "end",     "con",      "mg",       "bevel",    "c_interp", "d_interp", "lod", "shadow_obj",
        "trace_obj", "ctech", "stech", "maplib", "usemap"};
    return std::find(std::begin(ignored), std::end(ignored), k) != std::end(ignored);
}

RawMesh read_obj(const std::string& text) {
    RawMesh raw;
    raw.triangle_place = "line";
    raw.vertex_place = "line";
    struct Ref {
        int64_t index;  // as written, 1-based or negative
        uint64_t line;
        size_t vertices_before;
    };
    std::vector<Ref> refs;
    std::vector<std::pair<uint64_t, size_t>> faces;  // line, number of corners
    for (const Line& line : content_lines(text)) {
        const std::string_view key = line.tokens[0];
        if (key == "v") {
            if (line.tokens.size() < 4) {
                raw.error = at_line(line.number, "vertex needs 3 coordinates");
                return raw;
            }
            Vec3 p;
            for (int i = 0; i < 3; ++i)
                if (!parse_double(line.tokens[1 + i], p[i])) {
                    raw.error = at_line(line.number, "bad coordinate '" + printable(line.tokens[1 + i]) + "'");
                    return raw;
                }
            raw.mesh.vertices.push_back(p);
            raw.vertex_source.push_back(line.number);
        } else if (key == "f") {
            if (line.tokens.size() < 4) {
                raw.error = at_line(line.number, "face needs at least 3 vertices");
                return raw;
            }
            for (size_t i = 1; i < line.tokens.size(); ++i) {
                const std::string_view tok = line.tokens[i];
                int64_t index = 0;
                if (!parse_int(tok.substr(0, tok.find('/')), index) || index == 0) {
                    raw.error = at_line(line.number, "bad vertex reference '" + printable(tok) + "'");
                    return raw;
                }
                refs.push_back({index, line.number, raw.mesh.vertices.size()});
            }
            faces.push_back({line.number, line.tokens.size() - 1});
        } else if (!obj_ignored_statement(key)) {
            raw.error = at_line(line.number, "unknown statement '" + printable(key) + "'");
            return raw;
        }
    }
    // Indices are resolved after the whole file, so a face may refer to a later vertex.
    const size_t nv = raw.mesh.vertices.size();
    size_t r = 0;
    std::vector<uint32_t> poly;
    for (const auto& [line, corners] : faces) {
        poly.clear();
        for (size_t c = 0; c < corners; ++c, ++r) {
            const Ref& ref = refs[r];
            const int64_t zero_based = ref.index > 0 ? ref.index - 1 : int64_t(ref.vertices_before) + ref.index;
            if (zero_based < 0 || zero_based >= int64_t(nv)) {
                raw.error = at_line(line, "vertex index " + std::to_string(ref.index) + " out of range (" +
                                              std::to_string(nv) + " vertices)");
                return raw;
            }
            poly.push_back(uint32_t(zero_based));
        }
        add_polygon(raw, poly, line);
    }
    return raw;
}

// ---- OFF ---------------------------------------------------------------------------------------

RawMesh read_off(const std::string& text) {
    RawMesh raw;
    raw.triangle_place = "line";
    raw.vertex_place = "line";
    const std::vector<Line> lines = content_lines(text);
    if (lines.empty()) {
        raw.error = "no content";
        return raw;
    }
    // Header: [ST][C][N]OFF, counts on the same or the next line.
    const std::string_view magic = lines[0].tokens[0];
    const bool is_off = magic.size() >= 3 && magic.substr(magic.size() - 3) == "OFF" &&
                        magic.substr(0, magic.size() - 3).find_first_not_of("STCN") == std::string_view::npos;
    if (!is_off) {
        raw.error = at_line(lines[0].number, "missing OFF header (found '" + printable(magic) + "')");
        return raw;
    }
    std::vector<std::pair<std::string_view, uint64_t>> counts;
    size_t li = 0;
    for (size_t i = 1; i < lines[0].tokens.size(); ++i) counts.push_back({lines[0].tokens[i], lines[0].number});
    if (!counts.empty() && counts[0].first == "BINARY") {
        raw.error = at_line(lines[0].number, "binary OFF is not supported");
        return raw;
    }
    ++li;
    if (counts.empty()) {
        if (li >= lines.size()) {
            raw.error = at_line(lines[0].number, "missing vertex and face counts");
            return raw;
        }
        for (auto tok : lines[li].tokens) counts.push_back({tok, lines[li].number});
        ++li;
    }
    int64_t nv = 0, nf = 0;
    if (counts.size() < 2 || !parse_int(counts[0].first, nv) || !parse_int(counts[1].first, nf) || nv < 0 ||
        nf < 0 || nv > int64_t(UINT32_MAX)) {
        raw.error = at_line(counts.empty() ? lines[0].number : counts[0].second, "bad vertex and face counts");
        return raw;
    }
    const uint64_t last_line = lines.back().number;
    for (int64_t v = 0; v < nv; ++v, ++li) {
        if (li >= lines.size()) {
            raw.error = at_line(last_line, "unexpected end of file: expected " + std::to_string(nv) +
                                               " vertices, found " + std::to_string(v));
            return raw;
        }
        const Line& line = lines[li];
        if (line.tokens.size() < 3) {
            raw.error = at_line(line.number, "vertex needs 3 coordinates");
            return raw;
        }
        Vec3 p;
        for (int i = 0; i < 3; ++i)
            if (!parse_double(line.tokens[i], p[i])) {
                raw.error = at_line(line.number, "bad coordinate '" + printable(line.tokens[i]) + "'");
                return raw;
            }
        raw.mesh.vertices.push_back(p);
        raw.vertex_source.push_back(line.number);
    }
    std::vector<uint32_t> poly;
    for (int64_t f = 0; f < nf; ++f, ++li) {
        if (li >= lines.size()) {
            raw.error = at_line(last_line, "unexpected end of file: expected " + std::to_string(nf) +
                                               " faces, found " + std::to_string(f));
            return raw;
        }
        const Line& line = lines[li];
        int64_t n = 0;
        if (!parse_int(line.tokens[0], n) || n < 3) {
            raw.error = at_line(line.number, "face must start with its vertex count (at least 3)");
            return raw;
        }
        if (int64_t(line.tokens.size()) < 1 + n) {
            raw.error = at_line(line.number, "face lists fewer than " + std::to_string(n) + " vertices");
            return raw;
        }
        poly.clear();
        for (int64_t i = 0; i < n; ++i) {  // tokens after the n indices are a colour
            int64_t index = 0;
            if (!parse_int(line.tokens[1 + i], index)) {
                raw.error = at_line(line.number, "bad vertex index '" + printable(line.tokens[1 + i]) + "'");
                return raw;
            }
            if (index < 0 || index >= nv) {
                raw.error = at_line(line.number, "vertex index " + std::to_string(index) + " out of range (" +
                                                      std::to_string(nv) + " vertices)");
                return raw;
            }
            poly.push_back(uint32_t(index));
        }
        add_polygon(raw, poly, line.number);
    }
    if (li < lines.size()) {
        raw.error = at_line(lines[li].number, "unexpected data after the last face");
        return raw;
    }
    return raw;
}

// ---- vertex merging ----------------------------------------------------------------------------

// Maps every vertex to the lowest-index vertex with exactly the same coordinates; only
// vertices with index >= first_mergeable are remapped. Needs finite coordinates.
std::vector<uint32_t> coincident_map(const std::vector<Vec3>& vertices, size_t first_mergeable) {
    std::vector<uint32_t> order(vertices.size());
    std::iota(order.begin(), order.end(), 0u);
    auto less = [&](uint32_t a, uint32_t b) {
        const Vec3 &p = vertices[a], &q = vertices[b];
        if (p.x != q.x) return p.x < q.x;
        if (p.y != q.y) return p.y < q.y;
        if (p.z != q.z) return p.z < q.z;
        return a < b;
    };
    std::sort(order.begin(), order.end(), less);
    std::vector<uint32_t> map(vertices.size());
    std::iota(map.begin(), map.end(), 0u);
    uint32_t first_of_group = 0;  // lowest index with these coordinates (sorted first)
    for (size_t i = 0; i < order.size(); ++i) {
        if (i == 0 || vertices[order[i]] != vertices[order[i - 1]]) first_of_group = order[i];
        else if (order[i] >= first_mergeable) map[order[i]] = first_of_group;
    }
    return map;
}

// Applies a vertex map and drops vertices no triangle uses any more, keeping their order.
void remap_and_compact(TriMesh& mesh, const std::vector<uint32_t>& map) {
    std::vector<uint32_t> new_index(mesh.vertices.size(), UINT32_MAX);
    for (auto& tri : mesh.triangles)
        for (auto& v : tri) v = map[v];
    for (const auto& tri : mesh.triangles)
        for (uint32_t v : tri) new_index[v] = 0;
    std::vector<Vec3> kept;
    for (size_t v = 0; v < mesh.vertices.size(); ++v)
        if (new_index[v] == 0) {
            new_index[v] = uint32_t(kept.size());
            kept.push_back(mesh.vertices[v]);
        }
    for (auto& tri : mesh.triangles)
        for (auto& v : tri) v = new_index[v];
    mesh.vertices = std::move(kept);
}

bool all_finite(const std::vector<Vec3>& vertices) {
    for (const Vec3& p : vertices)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
    return true;
}

void merge_coincident(TriMesh& mesh, size_t first_mergeable = 0) {
    if (!all_finite(mesh.vertices)) return;  // validation reports the coordinate; sorting NaN is undefined
    remap_and_compact(mesh, coincident_map(mesh.vertices, first_mergeable));
}

// ---- PLY and STL through OpenMesh --------------------------------------------------------------

struct OmTraits : OpenMesh::DefaultTraits {
    typedef OpenMesh::Vec3d Point;
    typedef OpenMesh::Vec3d Normal;
};
// A polygon mesh, so the face count matches the file's and we triangulate ourselves.
using OmMesh = OpenMesh::PolyMesh_ArrayKernelT<OmTraits>;

// OpenMesh's readers are singletons with state and print to a global stream: one at a time,
// with its own diagnostics silenced (we report faults ourselves).
std::mutex openmesh_mutex;

bool openmesh_read(const std::string& path, OmMesh& om) {
    std::lock_guard lock(openmesh_mutex);
    const bool was_enabled = omerr().is_enabled();
    omerr().disable();
    OpenMesh::IO::Options options;
    const bool ok = OpenMesh::IO::read_mesh(om, path, options);
    if (was_enabled) omerr().enable();
    return ok;
}

// Converts OpenMesh's result and checks that every face of the file made it: OpenMesh drops
// faces with repeated or invalid vertices, and re-adds faces it cannot connect (non-manifold or
// flipped) on fresh copies of their vertices; those copies (index >= file_vertices) are mapped
// back to the original vertices so that validation sees the faces as written.
RawMesh from_openmesh(const OmMesh& om, uint64_t file_faces, size_t file_vertices, const char* place) {
    RawMesh raw;
    raw.triangle_place = place;
    if (om.n_faces() != file_faces) {
        const uint64_t missing = file_faces > om.n_faces() ? file_faces - om.n_faces() : 0;
        raw.error = std::to_string(missing) + " of " + std::to_string(file_faces) +
                    " faces could not be added (repeated or invalid vertex index, or truncated file)";
        return raw;
    }
    raw.mesh.vertices.reserve(om.n_vertices());
    for (const auto& vh : om.vertices()) {
        const auto& p = om.point(vh);
        raw.mesh.vertices.push_back(Vec3(p[0], p[1], p[2]));
    }
    std::vector<uint32_t> poly;
    uint64_t face = 0;
    for (const auto& fh : om.faces()) {
        poly.clear();
        for (const auto& vh : om.fv_range(fh)) poly.push_back(uint32_t(vh.idx()));
        add_polygon(raw, poly, face++);
    }
    if (om.n_vertices() > file_vertices) merge_coincident(raw.mesh, file_vertices);
    return raw;
}

// Reads the counts from a PLY header (ascii even in binary files).
bool ply_header_counts(const std::string& data, uint64_t& vertices, uint64_t& faces, std::string& error) {
    const size_t end = data.find("end_header");
    if (data.compare(0, 3, "ply") != 0) {
        error = "line 1: missing 'ply' magic";
        return false;
    }
    if (end == std::string::npos) {
        error = "header: missing 'end_header'";
        return false;
    }
    bool have_vertices = false, have_faces = false;
    uint64_t number = 0;
    size_t pos = 0;
    while (pos < end) {
        size_t eol = data.find('\n', pos);
        if (eol == std::string::npos || eol > end) eol = end;
        ++number;
        auto tokens = split_tokens(std::string_view(data).substr(pos, eol - pos));
        pos = eol + 1;
        if (tokens.size() == 3 && tokens[0] == "element") {
            int64_t n = 0;
            if (!parse_int(tokens[2], n) || n < 0) {
                error = at_line(number, "bad element count '" + printable(tokens[2]) + "'");
                return false;
            }
            if (tokens[1] == "vertex") vertices = uint64_t(n), have_vertices = true;
            if (tokens[1] == "face") faces = uint64_t(n), have_faces = true;
        }
    }
    if (!have_vertices || !have_faces) {
        error = std::string("header: no '") + (have_vertices ? "element face" : "element vertex") + "' declared";
        return false;
    }
    return true;
}

RawMesh read_ply(const std::string& path, const std::string& data) {
    RawMesh raw;
    uint64_t nv = 0, nf = 0;
    if (!ply_header_counts(data, nv, nf, raw.error)) return raw;
    OmMesh om;
    if (!openmesh_read(path, om)) {
        raw.error = "not a readable PLY file (OpenMesh reader failed)";
        return raw;
    }
    if (om.n_vertices() < nv) {
        raw.error = "header declares " + std::to_string(nv) + " vertices, " + std::to_string(om.n_vertices()) +
                    " were read";
        return raw;
    }
    return from_openmesh(om, nf, size_t(nv), "face");
}

// Binary when the size matches the triangle count of the 84-byte header; else ascii, which
// must start with "solid".
RawMesh read_stl(const std::string& path, const std::string& data) {
    RawMesh raw;
    uint64_t facets = 0;
    uint32_t declared = 0;
    if (data.size() >= 84) std::memcpy(&declared, data.data() + 80, 4);
    const bool binary = data.size() >= 84 && data.size() == 84 + 50 * uint64_t(declared);
    if (!binary) {
        const size_t start = data.find_first_not_of(" \t\r\n");
        if (start == std::string::npos || data.compare(start, 5, "solid") != 0) {
            if (data.size() >= 84)
                raw.error = "binary STL header declares " + std::to_string(declared) + " triangles (" +
                            std::to_string(84 + 50 * uint64_t(declared)) + " bytes) but the file has " +
                            std::to_string(data.size()) + " bytes";
            else
                raw.error = "line 1: neither binary STL (too short) nor ascii STL (no 'solid')";
            return raw;
        }
        for (const auto tok : split_tokens(data))
            if (tok == "facet") ++facets;
        if (facets == 0) {
            raw.error = "ascii STL without any facet";
            return raw;
        }
    } else {
        facets = declared;
    }
    OmMesh om;
    if (!openmesh_read(path, om)) {
        raw.error = "not a readable STL file (OpenMesh reader failed)";
        return raw;
    }
    raw = from_openmesh(om, facets, 0, "facet");
    // STL stores three vertices per facet: weld the ones with equal coordinates.
    if (raw.error.empty()) merge_coincident(raw.mesh);
    return raw;
}

// ---- glTF / GLB --------------------------------------------------------------------------------

// Images are irrelevant to geometry: accept them undecoded.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                void*) {
    return true;
}

glm::dmat4 node_transform(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
        glm::dmat4 m(1.0);
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[size_t(4 * c + r)];
        return m;
    }
    glm::dmat4 t(1.0), r(1.0), s(1.0);
    if (node.translation.size() == 3)
        t[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
    if (node.rotation.size() == 4)  // glTF stores x, y, z, w
        r = glm::mat4_cast(glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]));
    if (node.scale.size() == 3) {
        s[0][0] = node.scale[0];
        s[1][1] = node.scale[1];
        s[2][2] = node.scale[2];
    }
    return t * r * s;
}

RawMesh read_gltf(const std::string& path, const std::string& data, bool binary) {
    RawMesh raw;
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    tinygltf::Model model;
    std::string err, warn;
    const std::string base_dir = fs::path(path).parent_path().string();
    if (data.size() > UINT32_MAX) {
        raw.error = "file too large";
        return raw;
    }
    const bool ok =
        binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(data.data()),
                                             unsigned(data.size()), base_dir)
               : loader.LoadASCIIFromString(&model, &err, &warn, data.data(), unsigned(data.size()), base_dir);
    if (!ok) {
        raw.error = err.empty() ? "not a readable glTF file" : one_line(err);
        return raw;
    }

    // Roots: the default scene's nodes, else every node that is no other node's child.
    std::vector<int> roots;
    if (!model.scenes.empty()) {
        const int scene = model.defaultScene >= 0 && size_t(model.defaultScene) < model.scenes.size()
                              ? model.defaultScene
                              : 0;
        roots = model.scenes[size_t(scene)].nodes;
    } else {
        std::vector<bool> is_child(model.nodes.size(), false);
        for (const auto& node : model.nodes)
            for (int c : node.children)
                if (c >= 0 && size_t(c) < model.nodes.size()) is_child[size_t(c)] = true;
        for (size_t i = 0; i < model.nodes.size(); ++i)
            if (!is_child[i]) roots.push_back(int(i));
    }
    std::vector<bool> visited(model.nodes.size(), false);
    std::vector<std::pair<int, glm::dmat4>> stack;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, glm::dmat4(1.0)});
    while (!stack.empty()) {
        const auto [index, parent] = stack.back();
        stack.pop_back();
        if (index < 0 || size_t(index) >= model.nodes.size()) {
            raw.error = "node " + std::to_string(index) + " does not exist";
            return raw;
        }
        if (visited[size_t(index)]) {
            raw.error = "node " + std::to_string(index) + " is reached twice (the node graph is not a tree)";
            return raw;
        }
        visited[size_t(index)] = true;
        const tinygltf::Node& node = model.nodes[size_t(index)];
        const glm::dmat4 world = parent * node_transform(node);
        if (node.mesh >= 0) {
            if (size_t(node.mesh) >= model.meshes.size()) {
                raw.error = "node " + std::to_string(index) + ": mesh " + std::to_string(node.mesh) +
                            " does not exist";
                return raw;
            }
            const auto& prims = model.meshes[size_t(node.mesh)].primitives;
            for (size_t p = 0; p < prims.size(); ++p) {
                std::string error;
                if (!append_gltf_triangles(model, prims[p], world, raw.mesh, error)) {
                    raw.error = "mesh " + std::to_string(node.mesh) + " primitive " + std::to_string(p) + ": " + error;
                    return raw;
                }
            }
        }
        for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.push_back({*it, world});
    }
    // Exporters split vertices at normal and texture seams: weld them back into one surface.
    merge_coincident(raw.mesh);
    return raw;
}

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

std::string place_of(const RawMesh& raw, const MeshFault& fault) {
    if (fault.triangle >= 0 && size_t(fault.triangle) < raw.triangle_source.size()) {
        const uint64_t source = raw.triangle_source[size_t(fault.triangle)];
        if (std::strcmp(raw.triangle_place, "line") != 0 && source == uint64_t(fault.triangle))
            return "";  // face k is triangle k: the message names it already
        return std::string(raw.triangle_place) + " " + std::to_string(source) + ": ";
    }
    if (fault.vertex >= 0 && size_t(fault.vertex) < raw.vertex_source.size())
        return std::string(raw.vertex_place) + " " + std::to_string(raw.vertex_source[size_t(fault.vertex)]) + ": ";
    return "";
}

}  // namespace

MeshLoad load_mesh(const std::string& path) {
    MeshLoad result;
    auto fail = [&](const std::string& what) {
        result.mesh = {};
        result.error = one_line(path + ": " + what);
        return result;
    };
    const std::string ext = lower_extension(path);
    if (ext != ".obj" && ext != ".off" && ext != ".stl" && ext != ".ply" && ext != ".gltf" && ext != ".glb")
        return fail("unknown mesh format '" + printable(ext) + "' (expected .obj, .off, .stl, .ply, .gltf or .glb)");
    std::string data, error;
    if (!read_whole_file(path, data, error)) return fail(error);
    if (data.find_first_not_of(" \t\r\n") == std::string::npos) return fail("empty file");

    RawMesh raw;
    try {
        if (ext == ".obj") raw = read_obj(data);
        else if (ext == ".off") raw = read_off(data);
        else if (ext == ".stl") raw = read_stl(path, data);
        else if (ext == ".ply") raw = read_ply(path, data);
        else raw = read_gltf(path, data, ext == ".glb");
    } catch (const std::exception& e) {
        return fail(std::string("read error: ") + e.what());
    }
    if (!raw.error.empty()) return fail(raw.error);

    const MeshFault fault = find_mesh_fault(raw.mesh);
    if (!fault.what.empty()) return fail(place_of(raw, fault) + fault.what);
    result.mesh = std::move(raw.mesh);
    return result;
}

bool write_obj(const TriMesh& mesh, const std::string& path, std::string* error) {
    auto fail = [&](const std::string& what) {
        if (error) *error = path + ": " + what;
        return false;
    };
    const std::string tmp = path + ".tmp";
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) return fail(std::string("cannot write: ") + std::strerror(errno));
    std::string out = "# " + std::to_string(mesh.vertices.size()) + " vertices, " +
                      std::to_string(mesh.triangles.size()) + " triangles, metres\n";
    char buf[128];
    for (const Vec3& p : mesh.vertices) {
        // Shortest text that reads back to the same double.
        char* end = buf;
        *end++ = 'v';
        for (int i = 0; i < 3; ++i) {
            *end++ = ' ';
            end = std::to_chars(end, buf + sizeof buf, p[i]).ptr;
        }
        *end++ = '\n';
        out.append(buf, end);
    }
    for (const auto& t : mesh.triangles) {
        const int n = std::snprintf(buf, sizeof buf, "f %u %u %u\n", t[0] + 1, t[1] + 1, t[2] + 1);
        out.append(buf, size_t(n));
    }
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
    return true;
}

}  // namespace sulcus
