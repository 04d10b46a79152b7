// The scene file `sulcus.scene/1` (JSON, see docs/scene-format.md) and its trajectory CSV.
#pragma once

#include "sulcus/engine/mesh.h"
#include "sulcus/engine/types.h"

#include <array>
#include <string>
#include <vector>

namespace sulcus {

// The haptic settings of a scene (seed paper eq. 3 and 4).
struct HapticSettings {
    double stiffness_N_per_m = 1000.0;             // K_e, translational rows (eq. 4)
    double rotational_stiffness_Nm_per_rad = 0.03; // K_e, rotational rows (eq. 4)
    double weight_translational = 1.0;             // M, translational rows (eq. 3), per m^2
    double weight_rotational = 1e-4;               // M, rotational rows (eq. 3), per rad^2
};

// What an object (or a region of one) is made of, for contact: rigid, or compliant; and its
// Coulomb friction against the tool.
struct ContactMaterial {
    std::string name;
    bool compliant = false;
    // Compliant: how far the surface gives way (depth, m) under a normal force (N), a
    // piecewise-linear curve through the origin given by its further points (force ascending),
    // stiffening (slope force/depth never decreasing), extended with its last slope. A linear
    // stiffness k is the one point (1 N, 1/k m).
    std::vector<std::array<double, 2>> yield_curve;  // (force N, depth m)
    double friction_static = 0.0;   // Coulomb coefficients, kinetic <= static
    double friction_kinetic = 0.0;
};

// Triangles of an object that take another material: those whose centroid lies within
// `radius_m` of `center` and whose outward normal n has n . normal >= min_cos (scene frame).
struct MaterialRegion {
    std::string name;
    int material = 0;  // index into SceneFile::materials
    Vec3 center{0.0};
    double radius_m = 0.0;
    Vec3 normal{0.0, 1.0, 0.0};
    double min_cos = -1.0;
};

struct SceneObject {
    std::string name;
    std::string mesh_path;  // resolved (relative to the scene file's folder)
    Pose pose;
    TriMesh mesh;
    int material = -1;  // index into SceneFile::materials; -1: rigid and frictionless
    std::vector<MaterialRegion> regions;  // later regions win over earlier ones
};

// One row of the trajectory: time in seconds and the haptic tool's pose.
struct TrajectorySample {
    double t = 0.0;
    Pose pose;
};

struct SceneFile {
    std::string path;
    std::string name;  // file name without folder and extension
    std::vector<SceneObject> objects;
    SceneObject tool;
    std::vector<ContactMaterial> materials;
    HapticSettings haptic;
    std::string trajectory_path;
    std::vector<TrajectorySample> trajectory;
    double rate_hz = 1000.0;
    std::vector<std::string> warnings;  // unknown keys and the like: "file: place: what"
};

struct SceneLoad {
    SceneFile scene;
    std::vector<std::string> errors;  // one line each: "file: place: what is wrong"
    bool ok() const { return errors.empty(); }
};

// Reads the scene, its meshes and its trajectory; validates everything it can.
SceneLoad load_scene(const std::string& path);

// Reads a trajectory CSV with the header t,x,y,z,qw,qx,qy,qz. Errors are appended to `errors`.
std::vector<TrajectorySample> load_trajectory(const std::string& path, std::vector<std::string>& errors);

// The haptic pose at time t: linear in position, slerp in orientation, clamped to the ends.
// `cursor` speeds up monotone sampling (pass the same variable on each call, starting at 0).
Pose sample_trajectory(const std::vector<TrajectorySample>& trajectory, double t, size_t& cursor);

}  // namespace sulcus
