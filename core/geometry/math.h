// math.h — the small host-side geometry kdray needs: Vec3, Aabb, and the functions on them.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

namespace kdray {

struct Vec3 {
    float x = 0, y = 0, z = 0;

    constexpr Vec3() = default;
    constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
    constexpr float operator[](int axis) const { return axis == 0 ? x : axis == 1 ? y : z; }
    constexpr float& operator[](int axis) { return axis == 0 ? x : axis == 1 ? y : z; }
};

constexpr Vec3 operator+(Vec3 a, Vec3 b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
constexpr Vec3 operator-(Vec3 a, Vec3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
constexpr Vec3 operator-(Vec3 a) {
    return {-a.x, -a.y, -a.z};
}
constexpr Vec3 operator*(Vec3 a, float s) {
    return {a.x * s, a.y * s, a.z * s};
}
constexpr Vec3 operator*(float s, Vec3 a) {
    return a * s;
}
constexpr Vec3 operator*(Vec3 a, Vec3 b) {
    return {a.x * b.x, a.y * b.y, a.z * b.z};
}
constexpr Vec3 operator/(Vec3 a, float s) {
    return {a.x / s, a.y / s, a.z / s};
}
constexpr bool operator==(Vec3 a, Vec3 b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

constexpr float dot(Vec3 a, Vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
constexpr Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3 a) {
    return std::sqrt(dot(a, a));
}
inline Vec3 normalize(Vec3 a) {
    return a / length(a);
}
constexpr Vec3 min(Vec3 a, Vec3 b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
constexpr Vec3 max(Vec3 a, Vec3 b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
constexpr Vec3 lerp(Vec3 a, Vec3 b, float t) {
    return a + (b - a) * t;
}
inline bool is_finite(Vec3 a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

/// A point or vector in double: the scene's own coordinates (OBJ vertices, the render file's
/// camera and lights) before SceneFrame maps them into the float frame that kdray traces in.
struct DVec3 {
    double x = 0, y = 0, z = 0;

    constexpr DVec3() = default;
    constexpr DVec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
    constexpr DVec3(Vec3 v) : x(v.x), y(v.y), z(v.z) {}  // exact: every float is a double
    constexpr double operator[](int axis) const { return axis == 0 ? x : axis == 1 ? y : z; }
    constexpr double& operator[](int axis) { return axis == 0 ? x : axis == 1 ? y : z; }
};

constexpr DVec3 operator+(DVec3 a, DVec3 b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
constexpr DVec3 operator-(DVec3 a, DVec3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
constexpr DVec3 operator*(DVec3 a, double s) {
    return {a.x * s, a.y * s, a.z * s};
}
constexpr bool operator==(DVec3 a, DVec3 b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}
constexpr double dot(DVec3 a, DVec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
constexpr DVec3 cross(DVec3 a, DVec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(DVec3 a) {
    return std::sqrt(dot(a, a));
}
inline bool is_finite(DVec3 a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

/// Axis-aligned box. The default box is empty (lo > hi), so growing it by any point gives that
/// point's box. A box may be flat (lo == hi on an axis): kd-trees have flat nodes.
struct Aabb {
    Vec3 lo{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
            std::numeric_limits<float>::infinity()};
    Vec3 hi{-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
            -std::numeric_limits<float>::infinity()};

    constexpr bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    constexpr void grow(Vec3 p) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
    constexpr void grow(const Aabb& b) {
        lo = min(lo, b.lo);
        hi = max(hi, b.hi);
    }
    constexpr Vec3 extent() const { return hi - lo; }
    /// Surface area; 0 for an empty box, and positive for a flat one with two non-zero extents.
    constexpr float area() const {
        if (empty()) return 0.0f;
        Vec3 e = extent();
        return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
    }
    constexpr int longest_axis() const {
        Vec3 e = extent();
        return e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    }
    constexpr bool contains(const Aabb& b) const {
        return lo.x <= b.lo.x && lo.y <= b.lo.y && lo.z <= b.lo.z && hi.x >= b.hi.x &&
               hi.y >= b.hi.y && hi.z >= b.hi.z;
    }
    /// Overlap including touching faces: a triangle lying in a node's face overlaps that node.
    constexpr bool overlaps(const Aabb& b) const {
        return lo.x <= b.hi.x && lo.y <= b.hi.y && lo.z <= b.hi.z && b.lo.x <= hi.x &&
               b.lo.y <= hi.y && b.lo.z <= hi.z;
    }
    static constexpr Aabb intersection(const Aabb& a, const Aabb& b) {
        Aabb r;
        r.lo = max(a.lo, b.lo);
        r.hi = min(a.hi, b.hi);
        return r;
    }
};

}  // namespace kdray
