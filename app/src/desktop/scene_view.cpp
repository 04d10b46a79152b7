#include "desktop/scene_view.h"

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/gtx/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

namespace sulcus::desktop {

namespace {

const char* const kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_view_proj;
uniform mat4 u_model;
uniform mat3 u_normal;
out vec3 v_world;
out vec3 v_normal;
void main() {
    vec4 world = u_model * vec4(a_position, 1.0);
    v_world = world.xyz;
    v_normal = u_normal * a_normal;
    gl_Position = u_view_proj * world;
}
)";

// Linear-space shading, sRGB-encoded at the end. Two-sided: a back face is lit as seen.
const char* const kFragmentShader = R"(#version 330 core
in vec3 v_world;
in vec3 v_normal;
uniform vec4 u_color;
uniform vec3 u_eye;
uniform float u_roughness;
uniform float u_metallic;
uniform int u_ids;
uniform vec4 u_id;
out vec4 o_color;
vec3 light(vec3 n, vec3 v, vec3 l, vec3 radiance, vec3 albedo, float shininess, vec3 spec_color) {
    float nl = max(dot(n, l), 0.0);
    vec3 h = normalize(l + v);
    float spec = pow(max(dot(n, h), 0.0), shininess) * (shininess + 8.0) / 25.13;
    return radiance * nl * (albedo + spec_color * spec);
}
void main() {
    if (u_ids != 0) { o_color = u_id; return; }
    vec3 n = normalize(v_normal);
    vec3 v = normalize(u_eye - v_world);
    if (dot(n, v) < 0.0) n = -n;
    vec3 base = u_color.rgb;
    vec3 albedo = base * (1.0 - u_metallic);
    vec3 spec_color = mix(vec3(0.04), base, u_metallic);
    float shininess = 2.0 / max(u_roughness * u_roughness * u_roughness * u_roughness, 1e-3) - 2.0;
    shininess = clamp(shininess, 2.0, 2000.0);
    // Key light over the viewer's right shoulder, fill from the left, both tied to the view so the
    // pocket being looked at is always lit; sky-ground ambient for shape.
    vec3 right = normalize(cross(-v, vec3(0.0, 1.0, 0.0)) + vec3(1e-6));
    vec3 up = cross(right, -v);
    vec3 key = normalize(v + 0.6 * right + 0.8 * up);
    vec3 fill = normalize(v - 0.8 * right + 0.1 * up);
    vec3 c = light(n, v, key, vec3(2.2), albedo, shininess, spec_color);
    c += light(n, v, fill, vec3(0.6), albedo, shininess, spec_color);
    float hemi = 0.5 + 0.5 * n.y;
    vec3 ambient = mix(vec3(0.10, 0.09, 0.08), vec3(0.22, 0.23, 0.26), hemi);
    c += albedo * ambient;
    // A metal has no diffuse colour: it shows what it reflects, here a soft studio surround that
    // is brighter toward the viewer's up, so steel reads as steel and not as black.
    vec3 r = reflect(-v, n);
    float env = 0.35 + 0.45 * clamp(0.5 + 0.5 * dot(r, up), 0.0, 1.0);
    c += spec_color * env * mix(1.0, 0.5, u_roughness);
    // Rim: edges facing away from the viewer darken slightly, which reads as depth.
    c *= mix(0.75, 1.0, pow(max(dot(n, v), 0.0), 0.3));
    c = c / (1.0 + 0.15 * c);  // soft shoulder instead of clipping
    o_color = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)), u_color.a);
}
)";

GLuint compile(GLenum type, const char* source, std::string& error) {
    const GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = {};
        glGetShaderInfoLog(s, sizeof log, nullptr, log);
        error = std::string("shader does not compile: ") + log;
        for (char& ch : error)
            if (ch == '\n') ch = ' ';
        glDeleteShader(s);
        return 0;
    }
    return s;
}

glm::dmat4 pose_matrix(const Pose& p) {
    glm::dmat4 m = glm::toMat4(p.orientation);
    m[3] = glm::dvec4(p.position, 1.0);
    return m;
}

ObjectKind kind_of(const std::string& name) {
    if (name.rfind("tooth", 0) == 0) return ObjectKind::Tooth;
    if (name.rfind("gingiva", 0) == 0) return ObjectKind::Gingiva;
    if (name.rfind("bone", 0) == 0) return ObjectKind::Bone;
    if (name.rfind("probe", 0) == 0) return ObjectKind::Probe;
    return ObjectKind::None;  // floor regions and anything unknown: not drawn
}

// Area-weighted vertex normals over the part's shared vertices.
std::vector<float> interleave(const TriMesh& mesh) {
    std::vector<Vec3> normals(mesh.vertices.size(), Vec3(0.0));
    for (const auto& t : mesh.triangles) {
        const Vec3& a = mesh.vertices[t[0]];
        const Vec3 n = glm::cross(mesh.vertices[t[1]] - a, mesh.vertices[t[2]] - a);
        for (uint32_t i : t) normals[i] += n;
    }
    std::vector<float> out;
    out.reserve(mesh.vertices.size() * 6);
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        const double len = glm::length(normals[i]);
        const Vec3 n = len > 0 ? normals[i] / len : Vec3(0, 1, 0);
        const Vec3& p = mesh.vertices[i];
        out.insert(out.end(), {float(p.x), float(p.y), float(p.z), float(n.x), float(n.y), float(n.z)});
    }
    return out;
}

}  // namespace

// Uploads a triangle mesh (positions and area-weighted normals) into a vertex array of `m`.
void SceneView::upload(const TriMesh& mesh, Mesh& m) {
    const std::vector<float> vertices = interleave(mesh);
    glGenVertexArrays(1, &m.vao);
    glBindVertexArray(m.vao);
    glGenBuffers(1, &m.vbo);
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(float)), vertices.data(), GL_STATIC_DRAW);
    glGenBuffers(1, &m.ebo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(mesh.triangles.size() * 3 * sizeof(uint32_t)),
                 mesh.triangles.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<const void*>(3 * sizeof(float)));
    glBindVertexArray(0);
    m.index_count = GLsizei(mesh.triangles.size() * 3);
}

void SceneView::release(Mesh& m) {
    if (!m.vao) return;
    glDeleteBuffers(1, &m.vbo);
    glDeleteBuffers(1, &m.ebo);
    glDeleteVertexArrays(1, &m.vao);
    m.vao = m.vbo = m.ebo = 0;
}

SceneView::~SceneView() {
    for (Mesh& m : meshes_) release(m);
    release(drop_);
    if (program_) glDeleteProgram(program_);
    for (Target& t : targets_) {
        if (!t.fbo) continue;
        glDeleteFramebuffers(1, &t.fbo);
        glDeleteFramebuffers(1, &t.resolve_fbo);
        glDeleteRenderbuffers(1, &t.color);
        glDeleteRenderbuffers(1, &t.depth);
        glDeleteTextures(1, &t.texture);
    }
}

std::string SceneView::init(const Asset& asset) {
    std::string error;
    const GLuint vs = compile(GL_VERTEX_SHADER, kVertexShader, error);
    if (!vs) return error;
    const GLuint fs = compile(GL_FRAGMENT_SHADER, kFragmentShader, error);
    if (!fs) return error;
    program_ = glCreateProgram();
    glAttachShader(program_, vs);
    glAttachShader(program_, fs);
    glLinkProgram(program_);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(program_, GL_LINK_STATUS, &ok);
    if (!ok) return "shader program does not link";
    u_view_proj_ = glGetUniformLocation(program_, "u_view_proj");
    u_model_ = glGetUniformLocation(program_, "u_model");
    u_normal_ = glGetUniformLocation(program_, "u_normal");
    u_color_ = glGetUniformLocation(program_, "u_color");
    u_eye_ = glGetUniformLocation(program_, "u_eye");
    u_rough_ = glGetUniformLocation(program_, "u_roughness");
    u_metal_ = glGetUniformLocation(program_, "u_metallic");
    u_ids_ = glGetUniformLocation(program_, "u_ids");
    u_id_ = glGetUniformLocation(program_, "u_id");

    box_min_ = Vec3(1e9);
    box_max_ = Vec3(-1e9);
    for (const AssetNode& node : asset.nodes) {
        const ObjectKind kind = kind_of(node.name);
        if (kind == ObjectKind::None) continue;
        const int fdi = node.extras.is_object() ? node.extras.value("fdi", 0) : 0;
        for (const MeshPart& part : node.parts) {
            if (part.mesh.triangles.empty()) continue;
            Mesh m;
            m.kind = kind;
            m.fdi = fdi;
            // The probe is drawn where the servo loop puts it: its vertices are in the probe frame.
            m.model = kind == ObjectKind::Probe ? glm::dmat4(1.0) : pose_matrix(node.pose);
            if (part.material >= 0 && part.material < int(asset.materials.size())) {
                const Material& mat = asset.materials[size_t(part.material)];
                for (int i = 0; i < 4; ++i) m.color[size_t(i)] = float(mat.base_color[size_t(i)]);
                m.roughness = float(mat.roughness);
                m.metallic = float(mat.metallic);
            }
            if (kind != ObjectKind::Probe) {
                for (const Vec3& v : part.mesh.vertices) {
                    const Vec3 w = Vec3(m.model * glm::dvec4(v, 1.0));
                    box_min_ = glm::min(box_min_, w);
                    box_max_ = glm::max(box_max_, w);
                }
            }
            upload(part.mesh, m);
            meshes_.push_back(m);
        }
    }
    if (meshes_.empty()) return "the case has nothing to draw (no tooth, gingiva, bone or probe node)";
    {
        // A unit sphere (latitude-longitude) for the drops of blood.
        TriMesh sphere;
        const int rings = 10, segments = 16;
        for (int i = 0; i <= rings; ++i) {
            const double th = std::numbers::pi * i / rings;
            for (int j = 0; j < segments; ++j) {
                const double ph = 2.0 * std::numbers::pi * j / segments;
                sphere.vertices.push_back(Vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)));
            }
        }
        for (int i = 0; i < rings; ++i)
            for (int j = 0; j < segments; ++j) {
                const uint32_t a = uint32_t(i * segments + j), b = uint32_t(i * segments + (j + 1) % segments);
                const uint32_t c = a + uint32_t(segments), d = b + uint32_t(segments);
                sphere.triangles.push_back({a, c, b});
                sphere.triangles.push_back({b, c, d});
            }
        upload(sphere, drop_);
        drop_.color = {0.45f, 0.01f, 0.02f, 1.0f};
        drop_.roughness = 0.15f;  // wet
    }

    // Teeth for the view presets: the case's site list (asset extras) gives each tooth's margin
    // points and its buccal direction.
    std::map<int, std::pair<Vec3, int>> centres;
    std::map<int, Vec3> buccal;
    if (asset.extras.contains("sites") && asset.extras["sites"].is_array()) {
        for (const auto& s : asset.extras["sites"]) {
            if (!s.is_object() || !s.contains("margin_point") || !s.contains("outward")) continue;
            const int fdi = s.value("fdi", 0);
            const auto& mp = s["margin_point"];
            const auto& out = s["outward"];
            if (!mp.is_array() || mp.size() != 3 || !out.is_array() || out.size() != 3) continue;
            auto& c = centres[fdi];
            c.first += Vec3(mp[0].get<double>(), mp[1].get<double>(), mp[2].get<double>());
            c.second += 1;
            if (s.value("site", "") == "B") buccal[fdi] = Vec3(out[0].get<double>(), out[1].get<double>(), out[2].get<double>());
        }
    }
    for (const auto& [fdi, c] : centres) {
        ToothSpot t;
        t.fdi = fdi;
        t.centre = c.first / double(c.second);
        t.buccal = buccal.count(fdi) ? buccal[fdi] : Vec3(0, 0, 1);
        teeth_.push_back(t);
    }
    return "";
}

void SceneView::draw_mesh(const Mesh& m, const glm::dmat4& model, const float* color, float alpha, bool ids,
                          int id_kind, int id_fdi) {
    const glm::mat4 mf(model);
    glUniformMatrix4fv(u_model_, 1, GL_FALSE, glm::value_ptr(mf));
    const glm::mat3 nm(glm::inverseTranspose(glm::dmat3(model)));
    glUniformMatrix3fv(u_normal_, 1, GL_FALSE, glm::value_ptr(nm));
    if (ids) {
        glUniform4f(u_id_, float(id_kind) / 255.0f, float(id_fdi) / 255.0f, 0.0f, 1.0f);
    } else {
        glUniform4f(u_color_, color[0], color[1], color[2], alpha);
        glUniform1f(u_rough_, m.roughness);
        glUniform1f(u_metal_, m.metallic);
    }
    glBindVertexArray(m.vao);
    glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
}

void SceneView::pass(const glm::dmat4& view_proj, const Vec3& eye, const Pose& graphic, const Pose& haptic,
                     const DrawOptions& o, bool ids) {
    glUseProgram(program_);
    const glm::mat4 vp(view_proj);
    glUniformMatrix4fv(u_view_proj_, 1, GL_FALSE, glm::value_ptr(vp));
    glUniform3f(u_eye_, float(eye.x), float(eye.y), float(eye.z));
    glUniform1i(u_ids_, ids ? 1 : 0);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LEQUAL);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);

    const glm::dmat4 graphic_m = pose_matrix(graphic);
    const glm::dmat4 haptic_m = pose_matrix(haptic);
    const double apart = glm::length(graphic.position - haptic.position);
    const double turned = 2.0 * std::acos(std::min(1.0, std::abs(glm::dot(graphic.orientation, haptic.orientation))));
    const bool ghost = o.show_ghost && (apart > o.ghost_threshold_m || turned > o.ghost_threshold_rad);
    const bool gingiva_opaque = o.gingiva_alpha >= 0.999;

    // Opaque: teeth, bone, the graphic probe, and the gingiva when it is opaque.
    for (const Mesh& m : meshes_) {
        if (m.kind == ObjectKind::Bone && !o.show_bone) continue;
        if (m.kind == ObjectKind::Gingiva && (!o.show_gingiva || !gingiva_opaque)) continue;
        float color[3] = {m.color[0], m.color[1], m.color[2]};
        if (m.kind == ObjectKind::Tooth && m.fdi == o.highlight_fdi) {
            for (float& c : color) c = std::min(1.0f, c * 1.08f + 0.05f);
        }
        const glm::dmat4 model = m.kind == ObjectKind::Probe ? graphic_m : m.model;
        draw_mesh(m, model, color, 1.0f, ids, int(m.kind), m.kind == ObjectKind::Tooth ? m.fdi : 0);
    }
    // The id pass leaves see-through gingiva out: what is seen through it is what counts.
    if (ids) return;
    for (const Vec3& at : o.bleeding) {
        glm::dmat4 m = glm::scale(glm::dmat4(1.0), Vec3(o.drop_radius_m));
        m[3] = glm::dvec4(at, 1.0);
        draw_mesh(drop_, m, drop_.color.data(), 1.0f, false, 0, 0);
    }

    // Translucent: the ghost and see-through gingiva, without writing depth, back faces first.
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
    if (ghost) {
        const float red[3] = {0.9f, 0.08f, 0.06f};
        glEnable(GL_CULL_FACE);
        for (GLenum face : {GL_FRONT, GL_BACK}) {
            glCullFace(face);
            for (const Mesh& m : meshes_)
                if (m.kind == ObjectKind::Probe) draw_mesh(m, haptic_m, red, 0.35f, false, 0, 0);
        }
    }
    if (o.show_gingiva && !gingiva_opaque) {
        glEnable(GL_CULL_FACE);
        for (GLenum face : {GL_FRONT, GL_BACK}) {
            glCullFace(face);
            for (const Mesh& m : meshes_)
                if (m.kind == ObjectKind::Gingiva)
                    draw_mesh(m, m.model, m.color.data(), float(o.gingiva_alpha), false, 0, 0);
        }
    }
    glDisable(GL_CULL_FACE);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
}

void SceneView::draw(const OrbitCamera& camera, int x, int y, int w, int h, const Pose& graphic,
                     const Pose& haptic, const DrawOptions& options) {
    if (w <= 0 || h <= 0) return;
    glViewport(x, y, w, h);
    glEnable(GL_SCISSOR_TEST);
    glScissor(x, y, w, h);
    glClearColor(options.background[0], options.background[1], options.background[2], 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glDisable(GL_SCISSOR_TEST);
    const glm::dmat4 vp = camera.projection(double(w) / double(h)) * camera.view();
    pass(vp, camera.eye(), graphic, haptic, options, false);
}

void SceneView::draw_ids(const OrbitCamera& camera, int x, int y, int w, int h, const Pose& graphic,
                         const Pose& haptic, const DrawOptions& options) {
    if (w <= 0 || h <= 0) return;
    glViewport(x, y, w, h);
    glEnable(GL_SCISSOR_TEST);
    glScissor(x, y, w, h);
    glClearColor(0, 0, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glDisable(GL_SCISSOR_TEST);
    const glm::dmat4 vp = camera.projection(double(w) / double(h)) * camera.view();
    pass(vp, camera.eye(), graphic, haptic, options, true);
}

GLuint SceneView::draw_offscreen(int slot, const OrbitCamera& camera, int w, int h, int samples,
                                 const Pose& graphic, const Pose& haptic, const DrawOptions& options) {
    if (w <= 0 || h <= 0 || slot < 0 || slot > 1) return 0;
    Target& t = targets_[slot];
    if (w != t.w || h != t.h || samples != t.samples) {
        if (!t.fbo) {
            glGenFramebuffers(1, &t.fbo);
            glGenRenderbuffers(1, &t.color);
            glGenRenderbuffers(1, &t.depth);
            glGenFramebuffers(1, &t.resolve_fbo);
            glGenTextures(1, &t.texture);
        }
        glBindRenderbuffer(GL_RENDERBUFFER, t.color);
        glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, w, h);
        glBindRenderbuffer(GL_RENDERBUFFER, t.depth);
        glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w, h);
        glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t.color);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.depth);
        glBindTexture(GL_TEXTURE_2D, t.texture);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glBindFramebuffer(GL_FRAMEBUFFER, t.resolve_fbo);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.texture, 0);
        t.w = w;
        t.h = h;
        t.samples = samples;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    draw(camera, 0, 0, w, h, graphic, haptic, options);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t.fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, t.resolve_fbo);
    glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return t.texture;
}

void SceneView::blit(int slot) {
    const Target& t = targets_[slot];
    if (!t.resolve_fbo) return;
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t.resolve_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    glBlitFramebuffer(0, 0, t.w, t.h, 0, 0, t.w, t.h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

}  // namespace sulcus::desktop
