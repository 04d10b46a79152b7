// Procedural permanent teeth by FDI number (11-17, 21-27, 31-37, 41-47): the class shape
// (incisor, canine, premolar, molar with two or three roots and a furcation) sized from a
// standard dental-anatomy table (tooth_table.cpp names its source; docs/anatomy.md).
//
// Tooth frame (DESIGN.md): origin at the centre of the cervical line, +Y along the long axis toward
// the occlusal/incisal edge, +X toward mesial, +Z toward buccal/labial. Concretely, y = 0 is the
// height of the cemento-enamel junction (CEJ) on the facial surface, where the crown length and the
// root length are measured from; the CEJ rises toward the occlusal on the proximal surfaces by the
// table's curvature. Polar angles around the long axis are theta = atan2(z, x): 0 mesial, pi/2
// buccal, pi distal, -pi/2 lingual. Metres everywhere in code; the table is in millimetres.
#pragma once

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

#include <array>
#include <string>
#include <vector>

namespace sulcus {

enum class ToothClass { CentralIncisor, LateralIncisor, Canine, FirstPremolar, SecondPremolar, FirstMolar, SecondMolar };

// One row of the anatomy table, millimetres.
struct ToothDimensions {
    int fdi = 0;
    ToothClass cls = ToothClass::CentralIncisor;
    bool upper = true;
    double crown_length_mm = 0;     // facial CEJ to incisal edge / tip of the buccal cusp
    double root_length_mm = 0;      // CEJ to apex of the longest root
    double crown_md_mm = 0;         // mesiodistal diameter of the crown (at the contact areas)
    double cervix_md_mm = 0;        // mesiodistal diameter at the cervix
    double crown_bl_mm = 0;         // labio/bucco-lingual diameter of the crown (height of contour)
    double cervix_bl_mm = 0;        // labio/bucco-lingual diameter at the cervix
    double cej_curve_mesial_mm = 0; // rise of the CEJ on the mesial surface above its facial height
    double cej_curve_distal_mm = 0; // same on the distal surface
    int roots = 1;                  // 1, 2 or 3
    double trunk_length_mm = 0;     // CEJ to the furcation entrance (multi-rooted teeth), facial side
};

// Supported FDI numbers: 11-17, 21-27, 31-37, 41-47.
bool is_supported_tooth(int fdi);
std::vector<int> supported_teeth();
// Throws std::invalid_argument for an unsupported number.
const ToothDimensions& tooth_dimensions(int fdi);
// Universal (ADA) number 1-32 of an FDI permanent tooth (0 if not a permanent tooth number).
int universal_number(int fdi);

enum class Site { MB, B, DB, ML, L, DL };
inline constexpr std::array<Site, 6> kAllSites{Site::MB, Site::B, Site::DB, Site::ML, Site::L, Site::DL};
const char* site_name(Site s);          // "MB", "B", ...
bool parse_site(const std::string& name, Site* out);

// Furcation entrances: B and L for lower molars; B, M (approached from the palatal) and D for upper
// molars; M and D for the upper first premolar (buccal and palatal roots).
enum class FurcationSide { B, L, M, D };

// The implicit solid of one tooth in its tooth frame.
class ToothShape {
public:
    explicit ToothShape(int fdi);  // throws std::invalid_argument for an unsupported number

    const ToothDimensions& dims() const { return dims_; }
    // Negative inside, positive outside, close to the signed distance in metres near the surface
    // (within a factor of about 2), continuous everywhere.
    double field(const Vec3& p) const;
    // A box (tooth frame, metres) that contains the solid with a margin of at least 0.5 mm.
    Aabb bounds() const;
    // Height y (metres) of the CEJ at polar angle theta; smooth and periodic; equal to 0 at the
    // facial (theta = pi/2) and lingual, rising by the table's curvature at mesial and distal.
    double cej_height(double theta_rad) const;
    // Polar angle of a probing site: B and L at pi/2 and -pi/2; MB, DB, ML, DL at the line angles
    // of the cervical cross-section.
    double site_angle(Site s) const;
    // Furcation entrances of this tooth (empty for single-rooted teeth), with the position of each
    // entrance (tooth frame, metres: the roof of the furcation where the roots part, on the
    // outline) and the horizontal direction into the furcation (unit, in the XZ plane).
    struct Furcation {
        FurcationSide side;
        Vec3 entrance;
        Vec3 inward;
        double roof_height;  // y of the furcation roof (fornix), metres
        double width;        // distance between the roots at the entrance (narrowest free span 1 mm
                             // below the roof), metres
    };
    std::vector<Furcation> furcations() const;

private:
    // Shape parameters derived from the table, in millimetres (tooth_shape.cpp explains them).
    enum class Occlusal { Edge, Cusp, Table };
    struct Cusp {
        double x = 0, z = 0, height = 0, slope_x = 0, slope_z = 0;
    };
    struct Root {
        double top_y = 0, apex_y = 0;          // where the root leaves the trunk, and its apex
        double top_x = 0, top_z = 0, apex_x = 0, apex_z = 0, bend_x = 0, bend_z = 0;
        double half_md_top = 0, half_bl_top = 0, half_md_apex = 0, half_bl_apex = 0;
    };
    struct Section {
        double cx, half_md, half_facial, half_lingual, squareness;
    };
    Section section(double y) const;
    double body(double x, double y, double z) const;
    double root(const Root& r, double x, double y, double z) const;
    void occlusal(double x, double z, double* h, double* gx, double* gz) const;
    void find_furcations();

    ToothDimensions dims_;
    Occlusal occlusal_kind_ = Occlusal::Edge;
    double contact_y_ = 0, facial_contour_y_ = 0, lingual_contour_y_ = 0;  // heights of contour
    double top_half_md_ = 0, top_half_facial_ = 0, top_half_lingual_ = 0;  // section at the crown top
    double squareness_cervix_ = 0, squareness_crown_ = 0;
    double root_taper_length_ = 0;       // length over which the body's root part narrows
    double apex_half_md_ = 0, apex_half_bl_ = 0, apex_curve_ = 0;  // single root
    double edge_drop_mesial_ = 0, edge_drop_distal_ = 0;           // incisal corners
    std::array<Cusp, 7> cusps_{};  // cusps, then marginal ridges (slope_z = 0)
    int n_cusps_ = 0;
    std::array<Root, 3> roots_{};
    int n_roots_ = 0;               // separate roots (0: one root, part of the body)
    double blend_top_ = 0, blend_cusps_ = 0, blend_roots_ = 0;
    std::vector<Furcation> furcations_;
};

struct ToothMeshSettings {
    double cell_m = 1.5e-4;        // polygonizer grid
    double max_error_m = 2e-5;     // decimation error bound (0 = no decimation)
    size_t target_triangles = 0;   // decimation target (0 = error bound only)
};
// Visual preset: about 5k-20k triangles; collision preset: finer near the cervix is left to the
// decimation error bound.
ToothMeshSettings tooth_visual_settings();
ToothMeshSettings tooth_collision_settings();

// The tooth's closed surface in its tooth frame; passes validate_mesh.
TriMesh make_tooth_mesh(int fdi, const ToothMeshSettings& settings);

}  // namespace sulcus
