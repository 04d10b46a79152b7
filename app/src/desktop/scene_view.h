// Draws a case with OpenGL 3.3 core: teeth, bone and gingiva from the case asset (case.glb), the
// probe as the paper shows it — the graphic tool solid, the haptic tool as a translucent red ghost
// when the two differ — with its markings, and an object-id pass for picking and for checking a
// picture. Lighting: a key and a fill light (Blinn-Phong) over a hemispherical ambient, two-sided,
// in linear colour with an sRGB curve at the end; translucent gingiva is drawn after everything
// opaque, back faces then front faces, without writing depth.
#pragma once

#include "desktop/camera.h"
#include "desktop/gl.h"
#include "sulcus/content/asset.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace sulcus::desktop {

// What each object-id colour means (the red channel of the id pass; 0 = background).
enum class ObjectKind : uint8_t { None = 0, Tooth = 1, Gingiva = 2, Bone = 3, Probe = 4, Ghost = 5 };

struct DrawOptions {
    double gingiva_alpha = 1.0;  // 1 opaque; below 1 see-through
    bool show_gingiva = true;
    bool show_bone = true;
    bool show_ghost = true;
    double ghost_threshold_m = 0.05e-3;  // the ghost is drawn when the tools are further apart
    double ghost_threshold_rad = 0.02;
    std::array<float, 3> background{0.13f, 0.14f, 0.16f};  // linear
    int highlight_fdi = 0;  // a tooth drawn lighter (the chart's selection); 0 none
    std::vector<Vec3> bleeding;  // drops of blood at these points (bleeding on probing)
    double drop_radius_m = 0.35e-3;
};

class SceneView {
public:
    SceneView() = default;
    ~SceneView();
    SceneView(const SceneView&) = delete;
    SceneView& operator=(const SceneView&) = delete;

    // Compiles the shaders and uploads every node of the asset; floor regions (collision only)
    // are not drawn. Needs a current GL context. "" or one line saying what failed.
    std::string init(const Asset& asset);

    // Draws into the bound framebuffer's viewport (x, y, w, h in pixels), clearing it first.
    void draw(const OrbitCamera& camera, int x, int y, int w, int h, const Pose& graphic, const Pose& haptic,
              const DrawOptions& options);
    // The id pass into the bound framebuffer: each pixel's ObjectKind in red, the tooth's FDI
    // number in green (0 elsewhere), no lighting, no blending (the nearest surface wins).
    void draw_ids(const OrbitCamera& camera, int x, int y, int w, int h, const Pose& graphic, const Pose& haptic,
                  const DrawOptions& options);

    // Draws into offscreen target `slot` (0 or 1) of w x h pixels with `samples` per pixel (0: no
    // multisampling), resolved into a colour texture, and returns the texture: the main view (then
    // blit()) and the magnified inset shown in a panel.
    GLuint draw_offscreen(int slot, const OrbitCamera& camera, int w, int h, int samples, const Pose& graphic,
                          const Pose& haptic, const DrawOptions& options);
    // Copies target `slot`'s resolved picture into the default framebuffer at (0, 0).
    void blit(int slot);

    // Teeth as the view presets need them (from the tooth nodes' extras and vertices).
    const std::vector<ToothSpot>& teeth() const { return teeth_; }
    // Bounding box of everything drawn (metres).
    Vec3 box_min() const { return box_min_; }
    Vec3 box_max() const { return box_max_; }

private:
    struct Mesh {
        GLuint vao = 0, vbo = 0, ebo = 0;
        GLsizei index_count = 0;
        std::array<float, 4> color{0.8f, 0.8f, 0.8f, 1.0f};
        float roughness = 0.5f, metallic = 0.0f;
        ObjectKind kind = ObjectKind::None;
        int fdi = 0;
        glm::dmat4 model{1.0};  // node pose (probe meshes: identity, posed per draw)
    };
    void pass(const glm::dmat4& view_proj, const Vec3& eye, const Pose& graphic, const Pose& haptic,
              const DrawOptions& options, bool ids);
    void draw_mesh(const Mesh& m, const glm::dmat4& model, const float* color, float alpha, bool ids, int id_kind,
                   int id_fdi);
    static void upload(const TriMesh& mesh, Mesh& m);
    static void release(Mesh& m);

    GLuint program_ = 0;
    GLint u_view_proj_ = -1, u_model_ = -1, u_normal_ = -1, u_color_ = -1, u_eye_ = -1, u_rough_ = -1,
          u_metal_ = -1, u_ids_ = -1, u_id_ = -1;
    std::vector<Mesh> meshes_;
    Mesh drop_;  // unit sphere for the drops of blood
    std::vector<ToothSpot> teeth_;
    Vec3 box_min_{0.0}, box_max_{0.0};
    // Offscreen targets: multisampled (when asked), then resolved into a texture.
    struct Target {
        GLuint fbo = 0, color = 0, depth = 0, resolve_fbo = 0, texture = 0;
        int w = 0, h = 0, samples = -1;
    };
    Target targets_[2];
};

}  // namespace sulcus::desktop
