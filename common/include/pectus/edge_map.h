// Undirected edge -> incident faces, built from vertex indices (no vcg adjacency needed, so it
// works on any CMeshO whatever optional components are enabled).
#pragma once
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "pectus/cmesh.h"

namespace pectus {

class EdgeMap {
 public:
  explicit EdgeMap(const CMeshO& m);
  /// faces (indices into m.face) that use the edge {a,b}; empty if none
  const std::vector<int>& faces(int a, int b) const;
  template <class F> void forEach(F&& fn) const {
    for (const auto& kv : map_) fn(int(kv.first >> 32), int(kv.first & 0xffffffffu), kv.second);
  }
  std::size_t size() const { return map_.size(); }

 private:
  static std::uint64_t key(int a, int b) {
    if (a > b) std::swap(a, b);
    return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
  }
  std::unordered_map<std::uint64_t, std::vector<int>> map_;
  std::vector<int> empty_;
};

}  // namespace pectus
