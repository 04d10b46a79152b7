// Small scenes built in code for the renderer tests.
#pragma once

#include "sulcus/content/primitives.h"
#include "sulcus/engine/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

namespace sulcus::test {

inline SceneObject object(const std::string& name, const TriMesh& mesh, const Pose& pose = Pose{}) {
    SceneObject o;
    o.name = name;
    o.mesh = mesh;
    o.pose = pose;
    return o;
}

inline std::unique_ptr<Model> model_of(const TriMesh& tool, const std::vector<SceneObject>& objects,
                                       const RendererSettings& settings = RendererSettings{}) {
    ModelBuild b = build_model(tool, objects, settings);
    EXPECT_TRUE(b.model) << b.error;
    return std::move(b.model);
}

inline Quat axis_angle(const Vec3& axis, double angle_rad) { return glm::angleAxis(angle_rad, glm::normalize(axis)); }

inline Pose pose(const Vec3& p, const Quat& q = Quat(1, 0, 0, 0)) { return Pose{p, q}; }

constexpr double mm = 1e-3;

}  // namespace sulcus::test
