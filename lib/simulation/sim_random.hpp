// SPDX-License-Identifier: Apache-2.0
// Internal: the simulator's deterministic random numbers. Every draw of frame
// f comes from a generator seeded with (seed, f, stream), so a frame's noise
// does not depend on how many draws earlier frames made or on the call order.
#pragma once

#include <cmath>
#include <cstdint>

#include "core/crt_math.hpp"

namespace flt {

inline std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

// xoshiro256** (Blackman and Vigna): fast, 256-bit state, passes BigCrush.
class sim_rng {
  public:
    sim_rng(std::uint64_t seed, std::uint64_t frame, std::uint64_t stream) {
        std::uint64_t x = splitmix64(seed) ^ splitmix64(frame * 0xD1B54A32D192ED03ull + 1) ^
                          splitmix64(stream * 0x8CB92BA72F3D8DD7ull + 2);
        for (auto &w : state_)
            w = x = splitmix64(x);
    }
    std::uint64_t next() {
        const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
        const std::uint64_t t = state_[1] << 17;
        state_[2] ^= state_[0];
        state_[3] ^= state_[1];
        state_[1] ^= state_[2];
        state_[0] ^= state_[3];
        state_[2] ^= t;
        state_[3] = rotl(state_[3], 45);
        return result;
    }
    // [0, 1)
    double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }
    // N(0, 1) by Box-Muller: exact, for the few draws per frame (motion).
    double gauss() {
        const double a = uniform(), b = uniform();
        return std::sqrt(-2.0 * crt::log(1.0 - a)) * crt::cos(6.283185307179586 * b);
    }
    // Approximately N(0, 1): the scaled sum of four 16-bit uniforms (Irwin-Hall,
    // tails cut at 3.46 sigma), for per-pixel noise where speed matters and
    // the exact tail does not.
    float fast_gauss() {
        const std::uint64_t r = next();
        const std::uint32_t sum = std::uint32_t(r & 0xFFFF) + std::uint32_t((r >> 16) & 0xFFFF) +
                                  std::uint32_t((r >> 32) & 0xFFFF) + std::uint32_t(r >> 48);
        return (float(sum) - 131070.0f) * (1.0f / 37837.23f);
    }
    // Poisson(lambda) by Knuth's product method (lambda is small here).
    unsigned poisson(double lambda) {
        if (!(lambda > 0))
            return 0;
        if (lambda > 500)
            lambda = 500;
        const double limit = std::exp(-lambda);
        double p = uniform();
        unsigned k = 0;
        while (p > limit && k < 10000)
            p *= uniform(), ++k;
        return k;
    }

  private:
    static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    std::uint64_t state_[4];
};

}  // namespace flt
