#pragma once
// Stateless per-pixel randomness of the renderer (private to vio_simulator):
// values are functions of a key, so images do not depend on the order or
// the thread pixels are computed in.
#include <cstdint>

namespace vio::tools {

// splitmix64 finalizer: a fast, well-mixed 64-bit hash.
inline std::uint64_t Mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Uniform in [0, 1] from the low 8 bits.
inline float UnitFromBits(std::uint64_t bits) { return static_cast<float>(bits & 255u) * (1.0f / 255.0f); }

// Approximately standard normal from one hash: sum of four 16-bit uniforms.
inline float HashNormal(std::uint64_t h) {
  const float sum = static_cast<float>((h & 0xffff) + ((h >> 16) & 0xffff) + ((h >> 32) & 0xffff) + (h >> 48));
  return (sum * (1.0f / 65536.0f) - 2.0f) * 1.7320508f;  // var of each uniform is 1/12
}

// The noise hash of pixel `index` of the image with key `noise_key`.
inline std::uint64_t PixelHash(std::uint64_t noise_key, std::uint64_t index) {
  return Mix(noise_key * 0x2545f4914f6cdd1dULL + index);
}

}  // namespace vio::tools
