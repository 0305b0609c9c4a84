// test_float_float.cpp — the float-float arithmetic that devices without fp64 use for the
// triangle test's exact steps (core/device/kd_float_float.h, kd_traverse.h's *_ff functions),
// against long double (x86's 64-bit significand holds every exact value checked here) and closed
// forms: the error-free transformations are exact, the sum, product and quotient within their
// published bounds (against GCC's __float128, whose 113 bits hold those operands' exact sums), a b
// - c d correctly rounded and exact in sign on cancelling inputs, and the refined distance within
// an ulp of the exact one, as the double path is.
#include <doctest/doctest.h>

#include <cfloat>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/device/kd_traverse.h"

namespace {

using L = long double;
static_assert(std::numeric_limits<L>::digits >= 64, "exact checks need x87's long double");

constexpr L kU = L(1) / L(1 << 24);  // float's unit roundoff, 2^-24

/// Random floats of random sign, significand and binary exponent in [-lo_exp, hi_exp].
struct RandomFloats {
    std::mt19937 rng;
    int span;
    RandomFloats(std::uint32_t seed, int exponent_span) : rng(seed), span(exponent_span) {}
    float operator()() {
        std::uniform_real_distribution<float> significand(1.0f, 2.0f);
        std::uniform_int_distribution<int> exponent(-span, span), sign(0, 1);
        const float x = std::ldexp(significand(rng), exponent(rng));
        return sign(rng) ? -x : x;
    }
};

}  // namespace

TEST_CASE("float-float: TwoSum and TwoProduct are exact") {
    RandomFloats random(1, 16);
    for (int i = 0; i < 100000; ++i) {
        const float a = random(), b = random();
        float s, e, p, f;
        kd_two_sum(a, b, &s, &e);
        kd_two_product(a, b, &p, &f);
        REQUIRE(L(s) + L(e) == L(a) + L(b));
        REQUIRE(s == a + b);  // the leading part is the float sum
        REQUIRE(L(p) + L(f) == L(a) * L(b));
        REQUIRE(p == a * b);
        if (std::fabs(a) >= std::fabs(b)) {
            kd_fast_two_sum(a, b, &s, &e);
            REQUIRE(L(s) + L(e) == L(a) + L(b));
        }
    }
    // A closed form: (1 + 2^-23)^2 = 1 + 2^-22 + 2^-46, whose last term float drops.
    float p, e;
    kd_two_product(1.0f + FLT_EPSILON, 1.0f + FLT_EPSILON, &p, &e);
    CHECK(p == 1.0f + 2.0f * FLT_EPSILON);
    CHECK(e == std::ldexp(1.0f, -46));
}

TEST_CASE("float-float: sum, product and quotient within their error bounds") {
    // Exponents within +-6: a pair's parts then span at most 73 bits and any exact sum of two
    // pairs fits __float128's 113.
    using Q = __float128;
    auto relative = [](Q got, Q exact) {
        const Q error = got > exact ? got - exact : exact - got;
        return L(exact == 0 ? error : error / (exact > 0 ? exact : -exact));
    };
    RandomFloats random(2, 6);
    L worst_add = 0, worst_mul = 0, worst_div = 0;
    for (int i = 0; i < 100000; ++i) {
        // Normalised operands: hi = fl(hi + lo).
        float ah, al, bh, bl;
        kd_two_product(random(), random(), &ah, &al);
        kd_two_product(random(), random(), &bh, &bl);
        if (i % 4 == 0) {  // cancelling sums: b close to -a
            kd_two_sum(-ah, std::ldexp(random(), -36), &bh, &bl);
        }
        const Q a = Q(ah) + Q(al), b = Q(bh) + Q(bl);
        float h, l;
        kd_ff_add(ah, al, bh, bl, &h, &l);
        REQUIRE(h == h + l);  // normalised
        worst_add = std::max(worst_add, relative(Q(h) + Q(l), a + b));
        kd_ff_mul(ah, al, bh, bl, &h, &l);
        worst_mul = std::max(worst_mul, relative(Q(h) + Q(l), a * b));
        kd_ff_div(ah, al, bh, bl, &h, &l);
        worst_div = std::max(worst_div, relative(Q(h) + Q(l), a / b));
    }
    CAPTURE(double(worst_add / (kU * kU)));
    CAPTURE(double(worst_mul / (kU * kU)));
    CAPTURE(double(worst_div / (kU * kU)));
    // Joldes, Muller & Popescu 2017: 3u^2 (AccurateDWPlusDW), 5u^2 (DWTimesDW); the quotient's one
    // Newton step, a few u^2.
    CHECK(worst_add <= 3 * kU * kU);
    CHECK(worst_mul <= 5 * kU * kU);
    CHECK(worst_div <= 16 * kU * kU);
    // Not vacuous: these operands do need the low parts (a float sum is off by far more).
    CHECK(worst_add > 0);
}

TEST_CASE("float-float: a b - c d is correctly rounded and exact in sign") {
    int checked = 0, naive_wrong = 0;
    auto check = [&](float a, float b, float c, float d) {
        const L exact = L(a) * L(b) - L(c) * L(d);  // each product has 48 bits: exact
        const float got = kd_ff_diff_of_products(a, b, c, d);
        INFO(a, " ", b, " ", c, " ", d);
        REQUIRE((got > 0) == (exact > 0));
        REQUIRE((got < 0) == (exact < 0));
        REQUIRE(got == float(exact));
        // The double path the fp64 devices take: the same float.
        REQUIRE(got == float(double(a) * double(b) - double(c) * double(d)));
        naive_wrong += (a * b - c * d > 0) != (exact > 0) || (a * b - c * d < 0) != (exact < 0);
        ++checked;
    };
    // Closed forms: (1 + 2^-23)(1 - 2^-23) - 1 = -2^-46, which float rounds to 0.
    check(1.0f + FLT_EPSILON, 1.0f - FLT_EPSILON, 1.0f, 1.0f);
    CHECK(kd_ff_diff_of_products(1.0f + FLT_EPSILON, 1.0f - FLT_EPSILON, 1.0f, 1.0f) ==
          -std::ldexp(1.0f, -46));
    // Equal products from different factors are exactly 0.
    check(3.0f * 1024.0f, 5.0f, 5.0f * 1024.0f, 3.0f);
    check(0.1f, 0.3f, 0.3f, 0.1f);
    // Random, and nearly cancelling: c d = a b perturbed in its last bits, the edge functions of
    // a ray passing within rounding of an edge.
    RandomFloats random(3, 20);
    std::mt19937 rng(4);
    std::uniform_int_distribution<int> ulps(-3, 3);
    for (int i = 0; i < 100000; ++i) {
        const float a = random(), b = random();
        if (i % 2 == 0) {
            check(a, b, random(), random());
            continue;
        }
        // c = a * 2^k nudged, d = b / 2^k nudged: c d within a few ulps of a b.
        const int k = ulps(rng) * 3;
        float c = std::ldexp(a, k), d = std::ldexp(b, -k);
        for (int n = ulps(rng); n != 0; n += n > 0 ? -1 : 1)
            c = std::nextafter(c, n > 0 ? INFINITY : -INFINITY);
        for (int n = ulps(rng); n != 0; n += n > 0 ? -1 : 1)
            d = std::nextafter(d, n > 0 ? INFINITY : -INFINITY);
        check(a, b, c, d);
    }
    CHECK(checked > 100000);
    // The plain float expression gets a large share of these wrong in sign (or zero): what the
    // fallback exists for.
    CAPTURE(naive_wrong);
    CHECK(naive_wrong > 1000);
}

TEST_CASE("float-float: the edge fallback gives the double path's barycentrics") {
    // Sheared corners of rays passing within rounding of an edge: b = a scaled and nudged, so
    // u = cx by - cy bx and w = bx ay - by ax nearly cancel.
    RandomFloats random(6, 10);
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> nudge(-2, 2);
    int zeros_in_float = 0, differ = 0;
    for (int i = 0; i < 100000; ++i) {
        const float ax = random(), ay = random(), cx = random(), cy = random();
        const float s = std::ldexp(1.0f, nudge(rng));
        float bx = ax * s, by = ay * s;
        for (int n = nudge(rng); n != 0; n += n > 0 ? -1 : 1)
            by = std::nextafter(by, n > 0 ? INFINITY : -INFINITY);
        zeros_in_float += bx * ay - by * ax == 0.0f;
        float u[2], v[2], w[2];
        for (int fp64 = 0; fp64 < 2; ++fp64)
            kd_exact_edges(ax, ay, bx, by, cx, cy, fp64, &u[fp64], &v[fp64], &w[fp64]);
        differ += u[0] != u[1] || v[0] != v[1] || w[0] != w[1];
        REQUIRE((w[0] == 0.0f) == (L(bx) * L(ay) == L(by) * L(ax)));
    }
    CAPTURE(zeros_in_float);
    CHECK(zeros_in_float > 10000);  // the float test would have called these edge hits
    CHECK(differ == 0);
}

TEST_CASE("float-float: the refined distance is within an ulp of the exact one") {
    // Triangles of every shape (needles 1e4 long included) and rays from anywhere near them: the
    // float-float distance against long double from the same float corners and ray, and against
    // the double path.
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    int tested = 0, worst_ff = 0, worst_fp64 = 0, differ = 0;
    for (int i = 0; i < 50000; ++i) {
        const float scale = i % 2 ? 1.0f : 5000.0f;
        std::vector<float> tri(9);
        for (int k = 0; k < 9; ++k) tri[k] = unit(rng) * (k % 3 == 0 ? scale : 1.0f);
        const float o[3] = {unit(rng) * 3, unit(rng) * 3, unit(rng) * 3 + 4};
        const float d[3] = {unit(rng), unit(rng), unit(rng)};
        const float ff = kd_plane_distance_ff(tri.data(), o[0], o[1], o[2], d[0], d[1], d[2], NAN);
        const float fp64 =
            kd_plane_distance_fp64(tri.data(), o[0], o[1], o[2], d[0], d[1], d[2], NAN);
        L e1[3], e2[3], to[3];
        for (int a = 0; a < 3; ++a) {
            e1[a] = L(tri[3 + a]) - tri[a];
            e2[a] = L(tri[6 + a]) - tri[a];
            to[a] = L(tri[a]) - o[a];
        }
        const L n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
        const L along = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
        const L exact = (n[0] * to[0] + n[1] * to[1] + n[2] * to[2]) / along;
        if (!std::isfinite(float(exact)) || std::fabs(exact) > 1e6L) continue;
        ++tested;
        const float ulp =
            std::nextafter(std::fabs(float(exact)), INFINITY) - std::fabs(float(exact));
        worst_ff = std::max(worst_ff, int(std::fabs(L(ff) - exact) / ulp + 0.5L));
        worst_fp64 = std::max(worst_fp64, int(std::fabs(L(fp64) - exact) / ulp + 0.5L));
        differ += ff != fp64;
    }
    CAPTURE(tested);
    CAPTURE(worst_ff);
    CAPTURE(worst_fp64);
    CAPTURE(differ);
    CHECK(tested > 40000);
    CHECK(worst_ff <= 1);
    CHECK(worst_fp64 <= 1);
    CHECK(differ <= tested / 1000);
    // A ray parallel to the plane gives the fallback; so does a value past float's range.
    const float flat[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    CHECK(kd_plane_distance_ff(flat, 0, 0, 1, 1, 0, 0, 42.0f) == 42.0f);
    const float huge[9] = {0, 0, 1e30f, 1e30f, 0, 1e30f, 0, 1e30f, 1e30f};
    CHECK(kd_plane_distance_ff(huge, 0, 0, 0, 0, 0, 1e-30f, 42.0f) == 42.0f);
}
