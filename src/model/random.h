// hmsm's own deterministic PRNG: the same seed gives the same numbers on every platform and
// standard library (std:: distributions are implementation-defined, so they are not used).
#pragma once

#include <cmath>
#include <cstdint>

namespace hmsm::detail {

/// SplitMix64 seeding a xoshiro256** generator; uniform and normal conversions written here.
class Random {
public:
    explicit Random(uint64_t seed) {
        for (uint64_t& word : s_) word = splitmix(seed);
    }

    uint64_t next() {
        const uint64_t result = rotl(s_[1] * 5, 7) * 9;
        const uint64_t t = s_[1] << 17;
        s_[2] ^= s_[0];
        s_[3] ^= s_[1];
        s_[1] ^= s_[2];
        s_[0] ^= s_[3];
        s_[2] ^= t;
        s_[3] = rotl(s_[3], 45);
        return result;
    }

    /// Uniform in [0, 1) with 53 random bits.
    double uniform() { return double(next() >> 11) * 0x1.0p-53; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    /// Uniform integer in [0, n).
    uint64_t below(uint64_t n) { return n == 0 ? 0 : uint64_t(uniform() * double(n)) % n; }
    /// Standard normal by Box-Muller (uses two uniforms per call; no cached spare).
    double normal() {
        double u1 = uniform();
        double u2 = uniform();
        if (u1 < 1e-300) u1 = 1e-300;
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586476925 * u2);
    }
    double normal(double mean, double sigma) { return mean + sigma * normal(); }

private:
    static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    static uint64_t splitmix(uint64_t& x) {
        uint64_t z = (x += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    uint64_t s_[4];
};

}  // namespace hmsm::detail
