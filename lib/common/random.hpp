// The one seeding policy: every tool takes --seed; anything that needs an independent random
// stream (an episode, a worker, a restart) derives its seed from that one with derive_seed.
#pragma once

#include <cstdint>

namespace qte {

// SplitMix64 of (seed, index): well-mixed, distinct for distinct indices, non-negative as int64.
inline uint64_t derive_seed(uint64_t seed, uint64_t index) {
  uint64_t x = seed * 0x9e3779b97f4a7c15ull + index + 0x632be59bd9b4e019ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return (x ^ (x >> 31)) >> 1;
}

}  // namespace qte
