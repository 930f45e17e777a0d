// src/common/octahedral.h: the packed vertex layout's normal word (VertexLayout::packed). Known words,
// the decoding error over many directions (poles, axes, the lower-hemisphere fold seams) and the
// word surviving its trip through a float's bits.
#include "common/octahedral.h"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

using namespace hmsm::detail;

namespace {

/// Angle between two directions, accurate for tiny angles (atan2 of |a x b| and a . b).
double angle_between(const glm::dvec3& a, const glm::dvec3& b) {
    return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

/// Unit directions: a Fibonacci sphere, the poles and axes, the diagonals, and points on and
/// next to the seams where the lower hemisphere is folded (z = 0, x = 0, y = 0, |x| + |y| = 1).
std::vector<glm::dvec3> test_directions() {
    std::vector<glm::dvec3> dirs;
    const int n = 200000;
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z), phi = golden * i;
        dirs.push_back({r * std::cos(phi), r * std::sin(phi), z});
    }
    for (double s : {1.0, -1.0}) {
        dirs.push_back({s, 0, 0});
        dirs.push_back({0, s, 0});
        dirs.push_back({0, 0, s});
        dirs.push_back({-0.0 * s, 0, s});  // signed zeros on the fold
        for (double t : {1.0, -1.0}) {
            dirs.push_back({s, t, 0});
            dirs.push_back({s, 0, t});
            dirs.push_back({0, s, t});
            dirs.push_back({s, t, 1.0});
            dirs.push_back({s, t, -1.0});
        }
    }
    for (int i = 0; i <= 2000; ++i) {
        const double a = 2.0 * std::numbers::pi * i / 2000.0;
        for (double z : {0.0, -1e-7, 1e-7, -1e-3, 1e-3, -0.5, -0.999, -1.0 + 1e-9}) {
            dirs.push_back({std::cos(a), std::sin(a), z});
        }
        for (double y : {0.0, -0.0, 1e-6, -1e-6}) dirs.push_back({std::cos(a), y, std::sin(a)});
        for (double x : {0.0, -0.0, 1e-6, -1e-6}) dirs.push_back({x, std::cos(a), std::sin(a)});
    }
    for (glm::dvec3& d : dirs) d = glm::normalize(d);
    return dirs;
}

template <class T>
double max_decoding_error() {
    double worst = 0.0;
    for (const glm::dvec3& d : test_directions()) {
        const uint32_t word = encode_normal_word<T>(T(d.x), T(d.y), T(d.z));
        const UnitVector<T> n = decode_normal_word<T>(word);
        worst = std::max(worst, angle_between(d, glm::dvec3(n.x, n.y, n.z)));
        EXPECT_NEAR(std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z), 1.0, 1e-6);
    }
    return worst;
}

TEST(Octahedral, KnownWordsMatchPackSnorm2x16OfTheOctahedralPoint) {
    // packSnorm2x16: x in the low half, round(v * 32767) as int16.
    EXPECT_EQ(encode_normal_word(0.0f, 0.0f, 1.0f), 0x00000000u);
    EXPECT_EQ(encode_normal_word(1.0f, 0.0f, 0.0f), 0x00007fffu);
    EXPECT_EQ(encode_normal_word(-1.0f, 0.0f, 0.0f), 0x00008001u);
    EXPECT_EQ(encode_normal_word(0.0f, 1.0f, 0.0f), 0x7fff0000u);
    EXPECT_EQ(encode_normal_word(0.0f, -1.0f, 0.0f), 0x80010000u);
    EXPECT_EQ(encode_normal_word(0.0f, 0.0f, -1.0f), 0x7fff7fffu);  // the folded pole: (1, 1)
    // (0.6, -0.8, 0) / 1.4 = (0.428571, -0.571429): 14043 = 0x36db, -18724 = 0xb6dc.
    EXPECT_EQ(encode_normal_word(0.6f, -0.8f, 0.0f), 0xb6dc36dbu);
    // Lower hemisphere, (0.6, -0.8, -1) / 2.4 = (0.25, -0.333): folded to (0.666667, -0.75).
    EXPECT_EQ(encode_normal_word(0.6, -0.8, -1.0), uint32_t(21845) | (uint32_t(uint16_t(-24575)) << 16));
    const OctPoint<float> p = oct_encode(0.6f, -0.8f, -1.0f);
    EXPECT_FLOAT_EQ(p.x, 2.0f / 3.0f);
    EXPECT_FLOAT_EQ(p.y, -0.75f);
}

TEST(Octahedral, UnpackIsTheInverseOfPackOnEverySnorm16Pair) {
    for (int32_t i = -32767; i <= 32767; i += 7) {
        const uint32_t bits = uint32_t(uint16_t(int16_t(i)));
        const uint32_t word = bits | (uint32_t(uint16_t(int16_t(-i))) << 16);
        EXPECT_EQ(pack_snorm2x16(unpack_snorm2x16<float>(word)), word) << i;
    }
    // -32768 clamps to -1 like GLSL unpackSnorm2x16.
    EXPECT_EQ(unpack_snorm2x16<float>(0x80008000u).x, -1.0f);
}

TEST(Octahedral, DecodingErrorIsBelow1e4RadiansEverywhere) {
    const double float_error = max_decoding_error<float>();
    const double double_error = max_decoding_error<double>();
    EXPECT_LT(float_error, 1e-4);
    EXPECT_LT(double_error, 1e-4);
    // Not vacuous: the quantization step (2 / 65534 over the square) shows in the error.
    EXPECT_GT(double_error, 1e-6);
}

TEST(Octahedral, FloatAndDoubleEncodersAgreeAlmostEverywhere) {
    // The float encoder is the one every backend's float path uses; the double one (cpu64)
    // rounds nearly the same real number, so they differ only where the float quotient lands
    // within a few float ulps (about 3e-3 of a snorm16 step) of a rounding boundary, and then
    // by one step.
    int differing = 0, total = 0;
    for (const glm::dvec3& d : test_directions()) {
        const glm::vec3 f(d);
        const uint32_t a = encode_normal_word<float>(f.x, f.y, f.z);
        const uint32_t b = encode_normal_word<double>(f.x, f.y, f.z);
        ++total;
        if (a != b) {
            ++differing;
            for (int half : {0, 16}) {
                const int da = int16_t(uint16_t(a >> half)), db = int16_t(uint16_t(b >> half));
                EXPECT_LE(std::abs(da - db), 1);
            }
        }
    }
    EXPECT_LT(differing, total / 100);
}

TEST(Octahedral, WordsSurviveAsTheBitsOfAFloatAndAsADouble) {
    // Words whose float reading is a signalling NaN, a quiet NaN, an infinity, a denormal, -0.
    for (uint32_t word : {0xff800001u, 0x7f800001u, 0xffc00000u, 0x7f800000u, 0x00000001u,
                          0x80000000u, 0x7fff7fffu, 0xffffffffu}) {
        EXPECT_EQ(packed_word_from_w<float>(packed_word_to_w<float>(word)), word);
        EXPECT_EQ(packed_word_from_w<double>(packed_word_to_w<double>(word)), word);
    }
}

}  // namespace
