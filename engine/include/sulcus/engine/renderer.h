// The configuration-based 6-DOF haptic renderer (seed paper, sections II-IV).
//
// An immutable Model (tool and objects with their adjacency and BVHs, settings) and a small
// copyable State (graphic-tool pose, active contacts, solver warm start). One call to step() is
// one servo tick: given the haptic tool's pose it finds the graphic tool's pose as the solution
// of the constrained optimization of eq. 1-5, and the force and torque of eq. 4.
#pragma once

#include "sulcus/engine/bvh.h"
#include "sulcus/engine/mesh.h"
#include "sulcus/engine/qp.h"
#include "sulcus/engine/scene_file.h"
#include "sulcus/engine/types.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace sulcus {

// How the coordinates of a step are boxed (the local-solution box of eq. 5 and alternatives).
enum class LocalBox : uint8_t {
    // No coordinate box (the default). The step works in the frame of the tool at its last
    // graphic pose, so it is invariant to any rigid motion of the whole scene. The local solution
    // comes from the constraint sides fixed at the step's start, the force-continuity limit
    // (bounded motion per tick) and the passes round features.
    None,
    // Eq. 5 as printed: each coordinate, on the world axes, between the last graphic pose and the
    // haptic pose. It keeps the tool from jumping at contact switches in axis-aligned scenes, but
    // a face inclined to the axes pins coordinates the tool must slide along, and the tool
    // sticks while the force builds (docs/renderer.md).
    Paper,
    // Eq. 5's near side only, in the tool frame: no coordinate moves away from the haptic pose.
    TowardHaptic,
};

struct RendererSettings {
    HapticSettings haptic;
    LocalBox local_box = LocalBox::None;
    // Force continuity: per tick the graphic tool's offset from the haptic tool may change by at
    // most the haptic tool's own motion (translation plus radius times turn) plus this, in
    // metres, so the force changes by at most
    // K_t (|dp| + radius |dtheta| + force_step_margin_m) while the tool stays in contact (a
    // tool leaving contact goes straight to the haptic pose: no force at a distance). It is also
    // the speed (metres per tick) at which a graphic tool held back this way catches up.
    // <= 0 turns the limit off.
    double force_step_margin_m = 1e-5;
    // Largest violation of an exact (non-linearized) constraint accepted at the solution, in
    // metres. The step re-linearizes until every constraint is within it.
    double constraint_tol_m = 1e-7;
    // Re-linearizations of the constraints per QP candidate before the step gives up on it.
    int max_relinearizations = 12;
    // Candidate principal-contact sets solved in parallel per step (the default set included).
    int max_candidates = 8;
    // Two separating directions whose separations differ by less than this (metres) are taken as
    // tied: both become candidates.
    double tie_tol_m = 1e-6;
    // Distance under which the tool and an object count as touching (for contact statistics).
    double contact_distance_m = 1e-6;
    // Keep what detect measured about the triangles around each tool piece from tick to tick and
    // measure again only those whose verdict the tool's motion since could have changed; a later
    // pass of a tick likewise narrows the earlier pass's near set, and gather keeps the tool edges
    // near each object edge for the ticks after. Changes the step's cost, not its results (off:
    // every tick and pass measures from scratch).
    bool near_cache = true;
    // With the near cache, gather still looks at each triangle it passes over as quiet
    // (StepStats::quiet_triangles), and at all the vertices of one whose search it narrows to the
    // vertices listed near it, and counts those a vertex (not listed) had in fact come within the
    // bounds of (StepStats::quiet_featured), using nothing it finds of such a vertex: a check of
    // the cache, at a cost.
    bool audit_quiet_triangles = false;
    // With the near cache, the work a tick does ahead of need at its end (a slice of the next
    // superset of a piece's triangles, a tissue set gathered anew before the tool leaves it) waits
    // for a later tick when this one has already taken longer than this (microseconds, measured
    // on the step's clock), for as long as the room left allows: so that it seldom lands on a tick
    // that is heavy already (docs/performance.md). Changes when that work is done, never the
    // step's answers, which are the same to the bit whatever the clock says; the work of each
    // tick (StepStats' counts) then depends on the machine. Infinite: placed by the tick's counts
    // of work alone, the same on every run (headless replays, tests). A caller can also decide it
    // for each tick (State::defer), as the bench's later runs follow its first run's placement.
    double defer_after_us = 70.0;
    // With the near cache, an edge memo (the tool edges near an object edge) that a tick used
    // after it had moved past half its room is made anew at the tick's end, a few a tick, rather
    // than all of those made together running out at one later tick. Changes when that work is
    // done, never the step's answers (StepStats::edge_memos_ahead).
    bool edge_memos_ahead = true;
    // Leave out a candidate that swaps an atom holding nothing in the default set's answer for
    // its alternative (that answer the first QP from the step's start): it cannot have less
    // energy (docs/renderer.md, solve). Off: every candidate is solved. Changes the step's cost,
    // not which candidate wins.
    bool skip_idle_candidates = true;
    // Give up a candidate before its guard when its answer is already of no use to the step: an
    // alternative set's with no less energy than the best so far, a rescue's with more than the
    // rescue may take (docs/renderer.md, solve). The guard's planes only hold the tool further
    // from the target, so this changes the step's cost, not its answers. Off: every candidate's
    // answer is guarded.
    bool give_up_early = true;
    // Start each tick with the separating planes of the triangles whose planes held the tool at
    // the last tick (State::held_planes), rather than finding those triangles again by a QP and
    // a round of the guard: in the tissue the same few dozen gingiva triangles need planes tick
    // after tick. Off: every tick's guard finds them anew. Changes the step's answers (a carried
    // plane may hold the tool where a plane found anew would be found for a nearby triangle), not
    // what they guarantee.
    bool carry_planes = true;
    // Take a solution's virtual contacts (a vertex slid past the edge of the rigid face whose
    // plane holds it) round the feature within the pass: the atom is swapped for those of the
    // features the vertex faces at the solution and the set solved again, in place of another
    // pass of detect, gather and solve. Off: another pass. Changes the step's answers (the other
    // atoms stay as gathered at the pass's start), not what they guarantee.
    bool rescue_virtual = true;
    // Leave out of gather's set the atoms of compliant objects that cannot hold the tool anywhere
    // in the step's box: those that stay clear of the surface whatever the zone gives, and those a
    // zone's give covers, shallower than its deepest V-F atom by more than the box lets the tool
    // move (docs/renderer.md, compliant contacts); and count an edge pair in front of such an
    // object only within the reach, as on a rigid one. The exact problem is the same; the QP and
    // the exact checks work on fewer rows, so a solution may differ in its last bits (the
    // re-linearizations may also take another path to it, within the constraint tolerance; on the
    // bench's tissue runs the answers are 7e-18 m apart at most). Off: every atom in gather's
    // reach.
    bool drop_covered_atoms = true;
    qp::Settings qp;
};

// Springs of a compliant material at most (a yield curve of up to 8 points).
inline constexpr int kMaxMaterialSprings = 7;

// A contact material as the step uses it. A compliant one is a chain of springs in series, each
// but the last bottoming out at its cap: the exact form of a stiffening piecewise-linear yield
// curve (ContactMaterial), and in the QP one slack variable per spring with its stiffness in the
// objective.
struct ModelMaterial {
    bool compliant = false;
    int springs = 0;
    double stiffness_N_per_m[kMaxMaterialSprings] = {};
    double cap_m[kMaxMaterialSprings] = {};  // +infinity for the last spring
    double friction_static = 0.0;
    double friction_kinetic = 0.0;
};

// Depth (m) a material's surface gives way under a normal force (N): 0 for a rigid one.
double material_depth(const ModelMaterial& m, double force_N);

// One object of the scene with everything derived from its mesh.
struct ModelObject {
    std::string name;
    Pose pose;                 // local -> world
    TriMesh mesh;              // placed in the world (vertices already transformed)
    MeshTopology topology;
    Bvh bvh;                   // over the world-placed mesh
    // Contact zones (Model::zone_material): the object's own, and per triangle and vertex where
    // regions give some of it another material (empty when none do).
    uint16_t zone = 0;
    std::vector<uint16_t> triangle_zone;
    std::vector<uint16_t> vertex_zone;
    bool compliant = false;    // some zone of it is compliant
};

inline constexpr int kToolCapsules = 4;
// Slabs along each of a piece's two directions across its axis (ToolPiece::cross_range).
inline constexpr int kCrossCells = 16;
// Slabs along a piece's axis (ToolPiece::axial_first).
inline constexpr int kAxialCells = 64;
// Pieces a tool may have (the step keeps per-piece scratch of this size).
inline constexpr int kMaxToolPieces = 16;

// One convex piece of the tool: ranges into the ModelTool arrays (each piece's vertices,
// triangles, face planes and edges are contiguous) and its bounding capsules.
struct ToolPiece {
    uint32_t vertex_begin = 0, vertex_count = 0;
    uint32_t triangle_begin = 0, triangle_count = 0;
    uint32_t face_begin = 0, face_count = 0;
    uint32_t edge_begin = 0, edge_count = 0;
    // Bounding capsules along the piece's principal axis: the axis cut into kToolCapsules equal
    // pieces (capsule k runs from capsule_points[k] to [k + 1], tool frame), each with the radius
    // of the slab of the piece it covers. Cheap, tight lower bounds on distance for long pieces
    // such as a probe's tip and shank.
    std::array<Vec3, kToolCapsules + 1> capsule_points{};
    std::array<double, kToolCapsules> capsule_radii_m{};
    // Capsule k tapered: the hull of the balls of radii taper_radii_m[k][0] and [k][1] round its
    // two ends (each no more than capsule_radii_m[k]) still holds the slab of the piece it covers.
    // A tapering probe's slab lies far closer to it than to the capsule.
    std::array<std::array<double, 2>, kToolCapsules> taper_radii_m{};
    // How far a point outside the piece is over the face plane it is most in front of, at the
    // least, per metre of its distance from the piece (in [0, 1]; 1 for a piece without corners):
    // the least over the piece's vertices of how far the hull of the normals of the faces round
    // it lies from the origin. A point further than reach / plane_ratio from the piece is beyond
    // the reach of every F-V atom of it.
    double plane_ratio = 0.0;
    // kToolCapsules for a long piece (axis over four times its widest capsule), else 0: for a
    // compact piece the bounds are loose and cost more than they save.
    int capsule_count = 0;
    // Largest distance from the tool's origin to a vertex of this piece: a turn of theta moves
    // no point of the piece further than radius_m * theta (a probe's tip, near the origin, far
    // less than its handle).
    double radius_m = 0.0;
    // The centre of the piece's box (tool frame) and the largest distance of its vertices from it:
    // a motion moves no point of the piece further than the centre's displacement plus the turn
    // times spread_m.
    Vec3 centre{0.0};
    double spread_m = 0.0;
    // The boxes of the piece's edges (ModelTool::edges from edge_begin; tool frame) as lanes of
    // four: edge_boxes[b] holds those of the edges 4b to 4b + 3 of the piece, and
    // edge_block_boxes[g] the boxes of the four blocks 4g to 4g + 3 (each its edges' box). A lane
    // past the last edge or block holds an empty box. A query looks at a group's four block boxes
    // at once, then at the edges' boxes of each block that meets it: it finds the few tool edges
    // near an object edge without looking at every one, and in their order.
    struct BoxLanes {
        double lo[3][4];
        double hi[3][4];
    };
    std::vector<BoxLanes> edge_boxes;
    std::vector<BoxLanes> edge_block_boxes;
    // The piece's principal axis (unit, tool frame; the capsules lie along it). Its vertices in
    // order along it are ModelTool::axial_vertices[vertex_begin, + vertex_count), at
    // axial_coords (m): a ball around a point holds only the vertices of one run of them.
    Vec3 axis{0.0, 0.0, 1.0};
    // Across the axis: unit vectors cross_u and cross_w (tool frame) perpendicular to it and to
    // each other, each cut into kCrossCells slabs over the piece's extent along it (the lowest
    // at cross_lo_m, each 1 / cross_per_m thick). cross_range[k][i0 * kCrossCells + i1] has bit r
    // set when the vertex r-th along the axis (axial_vertices) lies in slabs i0 to i1 along
    // cross vector k. A ball holds no vertex outside the slabs its shadow meets along either,
    // nor outside its axial run: the three masks together leave the few it may hold. cross_cells
    // is 0 for a piece of over 64 vertices (the run alone then). The slabs are worth their
    // look-up for a ball whose shadow is under cross_narrow_m (m; 0 without them): a quarter of
    // the piece's narrower extent across.
    double cross_narrow_m = 0.0;
    Vec3 cross_u{1.0, 0.0, 0.0}, cross_w{0.0, 1.0, 0.0};
    std::array<double, 2> cross_lo_m{}, cross_per_m{};
    int cross_cells = 0;
    std::array<std::array<uint64_t, kCrossCells * kCrossCells>, 2> cross_range{};
    // The slab along cross vector k (0: cross_u, 1: cross_w) of coordinate c (m) there, clamped
    // to the slabs. Monotonic in c, so a range of coordinates meets the slabs between its ends'.
    int cross_cell(int k, double c) const {
        const double x = (c - cross_lo_m[size_t(k)]) * cross_per_m[size_t(k)];
        return !(x >= 1.0) ? 0 : x >= kCrossCells - 1 ? kCrossCells - 1 : int(x);
    }
    // Along the axis: kAxialCells slabs over the vertices' axial coordinates (the lowest at
    // axial_lo_m, each 1 / axial_per_m thick). The vertices in slabs i0 to i1 are the r-th along
    // the axis for r in [axial_first[i0], axial_first[i1 + 1]): where an axial run starts, and
    // whether it holds any vertex at all, by look-ups instead of a search.
    double axial_lo_m = 0.0, axial_per_m = 1.0;
    std::array<uint32_t, kAxialCells + 1> axial_first{};
    // The slab along the axis of axial coordinate c (m), clamped to the slabs; monotonic in c.
    int axial_cell(double c) const {
        const double x = (c - axial_lo_m) * axial_per_m;
        return !(x >= 1.0) ? 0 : x >= kAxialCells - 1 ? kAxialCells - 1 : int(x);
    }
    // Where the run of axial coordinates from `bottom` starts: the first r with
    // !(coords[r] < bottom), as std::lower_bound over the piece's coordinates `coords` (its
    // ModelTool::axial_coords) finds it, searching only bottom's slab.
    int axial_run_start(const double* coords, double bottom) const {
        const int cell = axial_cell(bottom);
        const int lo = int(axial_first[size_t(cell)]), hi = int(axial_first[size_t(cell + 1)]);
        if (lo == hi || !(coords[lo] < bottom)) return lo;
        if (coords[hi - 1] < bottom) return hi;
        return int(std::lower_bound(coords + lo, coords + hi, bottom) - coords);
    }
    // True when no vertex has an axial coordinate in [bottom, top]: the slabs between theirs
    // hold none (false decides nothing).
    bool axial_run_empty(double bottom, double top) const {
        return axial_first[size_t(axial_cell(bottom))] == axial_first[size_t(axial_cell(top) + 1)];
    }
    // The bits of the vertices in slabs i0 to i1 (i0 <= i1), for a piece of at most 64.
    uint64_t axial_mask(int i0, int i1) const {
        const uint32_t a = axial_first[size_t(i0)], b = axial_first[size_t(i1 + 1)];
        const uint64_t below_b = b >= 64 ? ~uint64_t(0) : (uint64_t(1) << b) - 1;
        const uint64_t below_a = a >= 64 ? ~uint64_t(0) : (uint64_t(1) << a) - 1;
        return below_b & ~below_a;
    }
    // Certified at build (closed, strictly convex, every vertex a corner or inside a flat face):
    // the vertex least along a direction is found by descending along the corners
    // (ModelTool::neighbours), not by looking at every vertex.
    bool descend = false;
};

// The tool: a rigid union of closed convex pieces (the connected components of its mesh, which
// may overlap), in its own frame, with their features.
struct ModelTool {
    TriMesh mesh;  // every piece, contiguous per piece
    MeshTopology topology;
    // Distinct face planes of each piece (coplanar triangles merged): unit normal and offset
    // (n . x = d on the plane, n . x <= d inside the piece), local frame.
    std::vector<Vec3> face_normals;
    std::vector<double> face_offsets;
    // Extent of the piece behind each face plane: offset minus the smallest n . v over its vertices.
    std::vector<double> face_depths;
    // Edges that are not flat (real edges of the convex pieces): vertex pairs (indices into
    // mesh.vertices, and the same relative to their piece's first vertex), and the unit normals of
    // the two triangles at each (local frame).
    std::vector<std::array<uint32_t, 2>> edges;
    std::vector<std::array<uint32_t, 2>> piece_edges;
    std::vector<std::array<Vec3, 2>> edge_normals;
    // The same two normals as indices of the piece's triangles (piece_triangle_normals): the
    // separating-axis test takes each triangle normal's dot product with a direction once, for
    // all the edges that share it.
    std::vector<std::array<uint32_t, 2>> edge_triangles;
    // Each piece's triangles' unit normals (local frame), contiguous per piece as piece_triangles.
    std::vector<Vec3> piece_triangle_normals;
    // Each edge as a segment in the local frame: its first vertex, the vector to its second, and
    // the reciprocal of that vector's squared length (0 for a point). The cheap cull of the tool
    // edges near an object edge works on them, in the tool's frame.
    struct EdgeLine {
        Vec3 from{0.0};
        Vec3 along{0.0};
        double inv_length2 = 0.0;
        double length2 = 0.0;  // the vector's squared length (m^2)
    };
    std::vector<EdgeLine> edge_lines;
    // Triangles with indices relative to their piece's first vertex.
    std::vector<std::array<uint32_t, 3>> piece_triangles;
    std::vector<uint8_t> vertex_piece;  // piece of each vertex
    // Each piece's vertices (indices into mesh.vertices) sorted by their coordinate along the
    // piece's axis (axial_coords, m, ascending), contiguous per piece as mesh.vertices.
    std::vector<uint32_t> axial_vertices;
    std::vector<double> axial_coords;
    // For the descent to the vertex least along a direction (ToolPiece::descend), indices
    // relative to the piece's first vertex: each corner's neighbouring corners along the piece's
    // edges (vertex i's, an index into mesh.vertices, are neighbours[neighbour_offsets[i],
    // neighbour_offsets[i + 1]); none for a vertex inside a flat face), and the corner a
    // descent from each vertex starts at (itself, or a corner of its face).
    std::vector<uint32_t> neighbour_offsets;
    std::vector<uint32_t> neighbours;
    std::vector<uint32_t> descent_start;
    std::vector<ToolPiece> pieces;
    double radius_m = 0.0;  // largest distance from the local origin to a vertex
};

struct Model {
    RendererSettings settings;
    ModelTool tool;
    std::vector<ModelObject> objects;
    // materials[0] is the default: rigid and frictionless.
    std::vector<ModelMaterial> materials;
    std::vector<uint16_t> zone_material;  // material of each contact zone
    // The direction a compliant zone gives way along (a region's normal: its surface translates
    // along it), or zero: each face of the zone gives way along its own normal (an object's own
    // material).
    std::vector<Vec3> zone_direction;
    // What the scene uses; the step computes nothing for what it does not.
    bool any_compliant = false;
    bool any_friction = false;
    // Distinct for every model built (copies share it): what the step's per-thread caches are
    // kept for.
    uint64_t serial = 0;
};

struct ModelBuild {
    std::unique_ptr<Model> model;
    std::string error;  // one line when the model cannot be built (e.g. a tool piece is not convex)
};

// `materials` are the scene's (SceneObject::material and regions index them).
ModelBuild build_model(const TriMesh& tool, const std::vector<SceneObject>& objects,
                       const RendererSettings& settings, const std::vector<ContactMaterial>& materials = {});

// The model of a loaded scene: its tool, objects and materials, with `settings` taking the
// scene's haptic settings.
ModelBuild build_model(const SceneFile& scene, RendererSettings settings);

// Springs in series of a yield curve (see ModelMaterial); "" or why the curve is not usable.
std::string material_from_curve(const ContactMaterial& in, ModelMaterial& out);

// Kinds of linearized constraint atoms (seed paper eq. 6 and 7).
enum class AtomKind : uint8_t {
    VertexFace,  // tool vertex against an object face plane (V-F, eq. 6)
    FaceVertex,  // object vertex against a tool face plane (F-V)
    EdgeEdge,    // tool edge against an object edge on the dynamic plane of eq. 7 (E-E)
    FixedAxis,   // tool vertex against a plane frozen for the step (fallback separating axis)
};

// A principal-contact constraint atom: one linearizable inequality g(q) >= 0 that can be
// re-evaluated exactly at any tool pose. Combination and degenerate principal contacts of
// Table 1 are sets of atoms.
struct Atom {
    AtomKind kind = AtomKind::VertexFace;
    uint16_t object = 0;
    uint32_t tool_vertex = 0;      // VF: the tool vertex
    uint32_t tool_face = 0;        // FV: tool face plane (ModelTool::face_normals)
    uint32_t tool_edge = 0;        // EE: tool edge (ModelTool::edges)
    uint32_t object_triangle = 0;  // VF: the constraining face
    uint32_t object_vertex = 0;    // FV: the object vertex
    uint32_t object_edge = 0;      // EE: object edge (MeshTopology::edges)
    double sign = 1.0;             // VF, EE: orientation of the normal, fixed once per step
    Vec3 axis{0.0};                // FixedAxis: unit normal (world); object_vertex is on the plane

    bool same_as(const Atom& o) const {
        return kind == o.kind && object == o.object && tool_vertex == o.tool_vertex && tool_face == o.tool_face &&
               tool_edge == o.tool_edge && object_triangle == o.object_triangle &&
               object_vertex == o.object_vertex && object_edge == o.object_edge && sign == o.sign;
    }
};

inline constexpr int kMaxActiveAtoms = 32;
// Triangles whose separating planes a tick carries to the next (State::held_planes).
inline constexpr int kMaxHeldPlanes = 64;

enum class StepStatus : uint8_t {
    Free,     // no constraint active: the graphic tool is at the haptic pose
    Contact,  // constrained: the graphic tool touches an object
    Partial,  // free of contact but short of the haptic pose: the motion of this tick was too
              // large to take whole, or the force-continuity limit is letting the tool catch up
    Held,     // no safe answer this tick: the last safe pose is kept
    BadInput, // the haptic pose was not finite or not a unit quaternion: last pose kept
};
inline constexpr int kStepStatusCount = 5;
const char* to_string(StepStatus s);

struct StageTimes {
    double detect_us = 0, gather_us = 0, solve_us = 0, select_us = 0, force_us = 0;
};

// The stages by number, in the order of the step, for tables and reports.
inline constexpr int kStageCount = 5;
inline constexpr const char* kStageNames[kStageCount] = {"detect", "gather", "solve", "select", "force"};
inline double stage_us(const StageTimes& t, int k) {
    const double v[kStageCount] = {t.detect_us, t.gather_us, t.solve_us, t.select_us, t.force_us};
    return v[k];
}

struct StepStats {
    StageTimes times;
    int triangles_near = 0;     // triangles within reach of this tick's motion (detect)
    // (triangle, tool piece) pairs put through a primitive test this tick: gather's feature
    // search, the solve's guard and the free-motion CCD.
    int triangles_tested = 0;
    // Sets of a compliant object's triangles near a piece gathered from the hierarchy this tick
    // (with the near cache): a piece's first, one where a piece left its set's box, or one set
    // ahead of need at the tick's end.
    int compliant_gathers = 0;
    // Triangles of such sets whose vertex search gather passed over this tick: no vertex of the
    // piece can have come within its bounds since the triangle was last looked at.
    int quiet_triangles = 0;
    // Of those, the ones a vertex had come within the bounds of (with audit_quiet_triangles; 0
    // when the cache holds what it should).
    int quiet_featured = 0;
    // Object edges whose nearby tool edges gather took from the piece's hierarchy this tick, not
    // from the memo of an earlier tick's; object vertices whose most-facing tool face it searched
    // for among all the piece's faces, not among those a memo kept.
    int edge_queries = 0;
    int face_searches = 0;
    // Of edge_queries, the memos made anew ahead of need at the tick's end
    // (RendererSettings::edge_memos_ahead).
    int edge_memos_ahead = 0;
    // Whether the work ahead of need waited for a later tick because this one had taken longer
    // than RendererSettings::defer_after_us (or State::defer said so).
    bool deferred = false;
    int atoms_gathered = 0;     // constraint atoms found within reach (gather)
    int candidates = 0;         // candidate principal-contact sets solved (gather/solve)
    int atoms = 0;              // constraint atoms in the chosen candidate
    int qp_solves = 0;
    int qp_iterations = 0;
    int relinearizations = 0;   // of the chosen candidate
    double constraint_error_m = 0.0;  // largest exact violation at the chosen pose (<= tol)
    int active_vf = 0, active_fv = 0, active_ee = 0;  // active atoms by kind
    int regions = 0;            // contact regions (connected parts of the contact)
    // The force-continuity limit would have left the tool hanging short of any contact, so it
    // was lifted for this tick: the tool fell onto the next contact or out of contact at once.
    bool released = false;
    // Extra passes of the stages this tick because a solution's contact was not real (held on
    // the extended plane of a face or the line of an edge past its end).
    int passes = 0;
    // Virtual contacts taken round within a pass instead (RendererSettings::rescue_virtual).
    int rescues = 0;
    // Gather found more tool-vertex features or atoms than it holds (deep in a compliant
    // object): the rest were left out, and the guard held the tool off what they would have.
    bool gather_truncated = false;
    // Compliance: zones giving way at the solution and the deepest of them (m).
    int soft_zones = 0;
    double soft_depth_m = 0.0;
    // Friction: the contacts' normal force (N), the static and kinetic limits of the tangential
    // force (sum of mu N over the contacts), and whether the tool slides (kinetic) this tick.
    double normal_force_N = 0.0;
    double friction_static_limit_N = 0.0;
    double friction_kinetic_limit_N = 0.0;
    bool sliding = false;
};

struct StepResult {
    Pose graphic;
    Vec3 force_N{0.0};
    Vec3 torque_Nm{0.0};
    StepStatus status = StepStatus::Free;
    int contacts = 0;  // active constraint atoms
    StepStats stats;
};

// How deep the tool is in each compliant object it has entered (m): per object, its deepest zone
// giving way at a solution. An object not listed is not entered. At most one entry per slack
// variable of the QP, so a solution's objects always fit. With the energy the zones' springs hold
// there, which the next step's box counts (a floor pressed in gives it back as the hand draws back).
inline constexpr int kMaxSoftObjects = qp::kMaxVars - qp::kPoseVars;

struct SoftDepths {
    int count = 0;
    uint16_t object[kMaxSoftObjects] = {};
    double depth_m[kMaxSoftObjects] = {};
    double spring_energy_J = 0.0;

    double of(uint16_t o) const {
        for (int i = 0; i < count; ++i)
            if (object[i] == o) return depth_m[i];
        return 0.0;
    }
    // Keeps the deeper of what is there and `d` for object o.
    void add(uint16_t o, double d) {
        for (int i = 0; i < count; ++i)
            if (object[i] == o) {
                if (d > depth_m[i]) depth_m[i] = d;
                return;
            }
        if (count < kMaxSoftObjects) {
            object[count] = o;
            depth_m[count++] = d;
        }
    }
};

struct State {
    Pose graphic;
    bool initialized = false;
    int active_count = 0;
    Atom active[kMaxActiveAtoms];
    Pose last_haptic;
    SoftDepths soft;            // how deep the tool is in each compliant object at the last tick's solution
    bool sliding = false;       // friction: the tool slid (kinetic) at the last tick
    // The (triangle, tool piece) pairs whose separating planes held the tool at the last tick's
    // answer (RendererSettings::carry_planes), each as (object << 40 | triangle << 8 | piece) + 1.
    int held_plane_count = 0;
    uint64_t held_planes[kMaxHeldPlanes] = {};
    // Which session this is (distinct per make_state) and how many ticks it has stepped: the step
    // carries what it learnt from tick to tick (RendererSettings::near_cache) only along one
    // session's own ticks, so a session stepped again from its start repeats itself exactly.
    uint64_t session = 0;
    uint64_t ticks = 0;
    // For the next step only, then back to -1: whether its work ahead of need waits as after a
    // tick longer than RendererSettings::defer_after_us (1), or not (0), instead of by its clock
    // (-1). Set from StepStats::deferred, it repeats another run's placement of that work.
    int defer = -1;
};

// Starts a state with the graphic tool at `pose` (which must not penetrate).
State make_state(const Pose& pose);

// One servo tick. Deterministic in its answers (and in its work too with
// RendererSettings::defer_after_us infinite, or State::defer set); no heap allocation, lock or
// I/O after the first call on a thread.
StepResult step(const Model& model, State& state, const Pose& haptic_pose);

// The 6-vector of eq. 4 in world frame: force K_t (p_g - p_h), torque K_r log(R_g R_h^-1).
void compute_wrench(const HapticSettings& h, const Pose& graphic, const Pose& haptic, Vec3& force_N,
                    Vec3& torque_Nm);

}  // namespace sulcus
