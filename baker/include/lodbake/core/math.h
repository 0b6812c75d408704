#pragma once
// Small fixed-size vectors. Float for storage (what files and GPUs hold), double for algorithms that
// accumulate (quadrics, areas, distances).

#include <cmath>

namespace lodbake {

constexpr double kPi = 3.14159265358979323846;

template <class T> struct Vec2 {
    T x = 0, y = 0;
    constexpr Vec2() = default;
    constexpr Vec2(T x_, T y_) : x(x_), y(y_) {}
    constexpr T& operator[](int i) { return i == 0 ? x : y; }
    constexpr T operator[](int i) const { return i == 0 ? x : y; }
    friend constexpr bool operator==(const Vec2& a, const Vec2& b) { return a.x == b.x && a.y == b.y; }
    friend constexpr bool operator!=(const Vec2& a, const Vec2& b) { return !(a == b); }
};

template <class T> struct Vec3 {
    T x = 0, y = 0, z = 0;
    constexpr Vec3() = default;
    constexpr Vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    template <class U> constexpr explicit Vec3(const Vec3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}
    constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    friend constexpr Vec3 operator+(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
    friend constexpr Vec3 operator-(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
    friend constexpr Vec3 operator*(const Vec3& a, T s) { return {a.x * s, a.y * s, a.z * s}; }
    friend constexpr Vec3 operator*(T s, const Vec3& a) { return {a.x * s, a.y * s, a.z * s}; }
    friend constexpr Vec3 operator/(const Vec3& a, T s) { return {a.x / s, a.y / s, a.z / s}; }
    constexpr Vec3& operator+=(const Vec3& b) { x += b.x; y += b.y; z += b.z; return *this; }
    constexpr Vec3& operator-=(const Vec3& b) { x -= b.x; y -= b.y; z -= b.z; return *this; }
    constexpr Vec3& operator*=(T s) { x *= s; y *= s; z *= s; return *this; }
    friend constexpr bool operator==(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
    friend constexpr bool operator!=(const Vec3& a, const Vec3& b) { return !(a == b); }
};

template <class T> struct Vec4 {
    T x = 0, y = 0, z = 0, w = 0;
    constexpr Vec4() = default;
    constexpr Vec4(T x_, T y_, T z_, T w_) : x(x_), y(y_), z(z_), w(w_) {}
    constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : (i == 2 ? z : w)); }
    constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : (i == 2 ? z : w)); }
    friend constexpr bool operator==(const Vec4& a, const Vec4& b) {
        return a.x == b.x && a.y == b.y && a.z == b.z && a.w == b.w;
    }
    friend constexpr bool operator!=(const Vec4& a, const Vec4& b) { return !(a == b); }
};

using Vec2f = Vec2<float>;
using Vec3f = Vec3<float>;
using Vec4f = Vec4<float>;
using Vec3d = Vec3<double>;

template <class T> constexpr T dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T> constexpr Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T> inline T length(const Vec3<T>& a) { return std::sqrt(dot(a, a)); }
template <class T> inline Vec3<T> normalize(const Vec3<T>& a) {
    T len = length(a);
    return len > T(0) ? a / len : Vec3<T>();
}
inline Vec3d toDouble(const Vec3f& v) { return Vec3d(v); }
/// double(float(x)): x rounded to the nearest float, for code that evaluates what a float will store.
/// The float goes through a volatile so that no optimiser can drop the rounding: GCC 12 folds a pair
/// of such round trips to x once its SLP vectorizer has turned them into vector conversions, and
/// GCC and Clang builds then disagree.
inline double roundToFloat(double x) {
    volatile float f = float(x);
    return double(f);
}
inline Vec3d roundToFloat(const Vec3d& v) { return {roundToFloat(v.x), roundToFloat(v.y), roundToFloat(v.z)}; }
inline bool isFinite(const Vec3f& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

} // namespace lodbake
