// Octahedral unit vectors (Cigolle et al. 2014, "A Survey of Efficient Representations for
// Independent Unit Vectors", JCGT 3(2)) in two snorm16: how VertexLayout::packed stores a vertex
// normal in the w of its position. Written once for C++ (the CPU passes and Simulation::read)
// and CUDA (kernels/cuda/contour.cu); the GLSL twin is shaders/glsl/octahedral.glsl, with the
// same names and the same operations in the same order, so that the three encoders agree bit for
// bit wherever their float division does (C++ and CUDA divide with correct rounding).
//
// The word is GLSL packSnorm2x16(oct_encode(n)): x in the low 16 bits, y in the high 16 bits,
// each round(clamp(v, -1, 1) * 32767) as a two's-complement int16. GLSL leaves the direction of
// an exact .5 tie to the implementation; here ties go to even, as in Mesa's packSnorm2x16.
#pragma once

#include "host_device.h"

#include <cmath>
#include <cstdint>
#include <cstring>

namespace hmsm::detail {

/// A point of the octahedral square [-1, 1]^2.
template <class T>
struct OctPoint {
    T x, y;
};

template <class T>
struct UnitVector {
    T x, y, z;
};

namespace octahedral_detail {
template <class T>
HMSM_HOST_DEVICE T magnitude(T v) { return v < T(0) ? -v : v; }
/// +1 for v >= 0 (including -0), else -1: GLSL's usual signNotZero.
template <class T>
HMSM_HOST_DEVICE T sign_not_zero(T v) { return v >= T(0) ? T(1) : T(-1); }
template <class T>
HMSM_HOST_DEVICE T clamp_unit(T v) { return v < T(-1) ? T(-1) : (v > T(1) ? T(1) : v); }
template <class T>
HMSM_HOST_DEVICE T round_half_even(T v) {
#ifdef __CUDA_ARCH__
    return rint(v);
#else
    return std::rint(v);  // the default rounding mode: to nearest, ties to even
#endif
}
template <class T>
HMSM_HOST_DEVICE T square_root(T v) {
#ifdef __CUDA_ARCH__
    return sqrt(v);
#else
    return std::sqrt(v);
#endif
}
template <class T>
HMSM_HOST_DEVICE uint32_t snorm16(T v) {
    return uint32_t(int32_t(round_half_even(clamp_unit(v) * T(32767)))) & 0xffffu;
}
template <class T>
HMSM_HOST_DEVICE T from_snorm16(uint32_t bits) {
    int32_t i = int32_t(bits & 0xffffu);
    if (i >= 0x8000) i -= 0x10000;
    return clamp_unit(T(i) / T(32767));
}
}  // namespace octahedral_detail

/// The octahedral point of the non-zero vector (x, y, z): projected onto |x|+|y|+|z| = 1, the
/// lower hemisphere (z < 0) folded over the diagonals.
template <class T>
HMSM_HOST_DEVICE OctPoint<T> oct_encode(T x, T y, T z) {
    using namespace octahedral_detail;
    const T l1 = magnitude(x) + magnitude(y) + magnitude(z);
    OctPoint<T> p{x / l1, y / l1};
    if (z < T(0))
        p = {(T(1) - magnitude(p.y)) * sign_not_zero(p.x), (T(1) - magnitude(p.x)) * sign_not_zero(p.y)};
    return p;
}

/// The unit vector of an octahedral point (the inverse of oct_encode up to quantization).
template <class T>
HMSM_HOST_DEVICE UnitVector<T> oct_decode(OctPoint<T> p) {
    using namespace octahedral_detail;
    T x = p.x, y = p.y;
    const T z = T(1) - magnitude(x) - magnitude(y);
    const T fold = z < T(0) ? -z : T(0);
    x += x >= T(0) ? -fold : fold;
    y += y >= T(0) ? -fold : fold;
    const T scale = T(1) / square_root(x * x + y * y + z * z);
    return {x * scale, y * scale, z * scale};
}

/// GLSL packSnorm2x16: x in the low 16 bits, y in the high 16 bits.
template <class T>
HMSM_HOST_DEVICE uint32_t pack_snorm2x16(OctPoint<T> p) {
    return octahedral_detail::snorm16(p.x) | (octahedral_detail::snorm16(p.y) << 16);
}

/// GLSL unpackSnorm2x16.
template <class T>
HMSM_HOST_DEVICE OctPoint<T> unpack_snorm2x16(uint32_t word) {
    return {octahedral_detail::from_snorm16<T>(word), octahedral_detail::from_snorm16<T>(word >> 16)};
}

/// The packed normal word of VertexLayout::packed: pack_snorm2x16(oct_encode(n)).
template <class T>
HMSM_HOST_DEVICE uint32_t encode_normal_word(T x, T y, T z) {
    return pack_snorm2x16(oct_encode(x, y, z));
}
/// The unit normal of a packed normal word: oct_decode(unpack_snorm2x16(word)).
template <class T>
HMSM_HOST_DEVICE UnitVector<T> decode_normal_word(uint32_t word) {
    return oct_decode(unpack_snorm2x16<T>(word));
}

/// GLSL uintBitsToFloat / floatBitsToUint: moves bits, never converts (a word may read as a NaN
/// or a denormal float, and must come back unchanged).
HMSM_HOST_DEVICE float float_from_bits(uint32_t word) {
#ifdef __CUDA_ARCH__
    return __uint_as_float(word);
#else
    float f;
    std::memcpy(&f, &word, sizeof f);
    return f;
#endif
}
HMSM_HOST_DEVICE uint32_t bits_from_float(float f) {
#ifdef __CUDA_ARCH__
    return __float_as_uint(f);
#else
    uint32_t word;
    std::memcpy(&word, &f, sizeof word);
    return word;
#endif
}

/// The w of a vertex_position element of precision T that holds a packed normal word: the word's
/// bits for float (every GPU backend and the float CPU path); for the double-precision CPU
/// oracle the word's integer value, exact in a double, since converting a float whose bits are
/// a signalling NaN to double quiets it and would change the word.
template <class T>
HMSM_HOST_DEVICE T packed_word_to_w(uint32_t word) {
    if constexpr (sizeof(T) == sizeof(float)) return float_from_bits(word);
    else return T(word);
}
/// The inverse of packed_word_to_w.
template <class T>
HMSM_HOST_DEVICE uint32_t packed_word_from_w(T w) {
    if constexpr (sizeof(T) == sizeof(float)) return bits_from_float(w);
    else return uint32_t(w);
}

}  // namespace hmsm::detail
