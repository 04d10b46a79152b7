// Basic value types shared by the whole engine: vectors, rotations, poses, boxes.
// Double precision, SI units (metres, radians) throughout.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cstdint>

namespace sulcus {

using Vec3 = glm::dvec3;
using Mat3 = glm::dmat3;
// Unit quaternion; glm's constructor order is (w, x, y, z), as in our files.
using Quat = glm::dquat;

// A rigid pose: maps the body's local frame to the world (x_world = R x_local + position).
struct Pose {
    Vec3 position{0.0, 0.0, 0.0};
    Quat orientation{1.0, 0.0, 0.0, 0.0};

    Vec3 apply(const Vec3& local) const { return orientation * local + position; }
    Vec3 rotate(const Vec3& local) const { return orientation * local; }
    Vec3 inverse_apply(const Vec3& world) const { return glm::conjugate(orientation) * (world - position); }
};

// Axis-aligned box in metres. An empty box has lo > hi.
struct Aabb {
    Vec3 lo{1e300, 1e300, 1e300};
    Vec3 hi{-1e300, -1e300, -1e300};

    void grow(const Vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void grow(const Aabb& b) {
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
    void inflate(double r) {
        lo -= Vec3(r);
        hi += Vec3(r);
    }
    bool overlaps(const Aabb& b) const {
        return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z &&
               b.lo.z <= hi.z;
    }
    // Whether box b lies inside this one.
    bool contains(const Aabb& b) const {
        return lo.x <= b.lo.x && lo.y <= b.lo.y && lo.z <= b.lo.z && b.hi.x <= hi.x && b.hi.y <= hi.y &&
               b.hi.z <= hi.z;
    }
    bool empty() const { return lo.x > hi.x; }
    Vec3 center() const { return 0.5 * (lo + hi); }
};

}  // namespace sulcus
