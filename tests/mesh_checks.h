// Checks on closed meshes for the tests: inside or outside by the solid angles.
#pragma once

#include "sulcus/engine/mesh.h"

#include <cmath>
#include <numbers>

namespace sulcus::test {

// Generalized winding number (solid angles): about 1 inside a closed outward mesh, 0 outside.
inline double winding_number(const TriMesh& m, const Vec3& p) {
    double sum = 0;
    for (const auto& t : m.triangles) {
        const Vec3 a = m.vertices[t[0]] - p, b = m.vertices[t[1]] - p, c = m.vertices[t[2]] - p;
        const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
        const double num = glm::dot(a, glm::cross(b, c));
        const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(a, c) * lb + glm::dot(b, c) * la;
        sum += 2.0 * std::atan2(num, den);
    }
    return sum / (4.0 * std::numbers::pi);
}

}  // namespace sulcus::test
