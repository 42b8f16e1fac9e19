// Undirected edge -> incident faces, built from vertex indices (no vcg adjacency needed, so it
// works on any CMeshO whatever optional components are enabled). Stored sorted (CSR): one sort of the
// faces' edges, no allocation per edge.
#pragma once
#include <cstdint>
#include <vector>

#include "pectus/cmesh.h"

namespace pectus {

class EdgeMap {
 public:
  /// the faces (indices into m.face, ascending) of one edge
  struct Faces {
    const int* first = nullptr;
    const int* last = nullptr;
    std::size_t size() const { return std::size_t(last - first); }
    bool empty() const { return first == last; }
    const int* begin() const { return first; }
    const int* end() const { return last; }
    int operator[](std::size_t i) const { return first[i]; }
  };
  explicit EdgeMap(const CMeshO& m);
  /// faces that use the edge {a,b}; empty if none
  Faces faces(int a, int b) const;
  /// fn(a, b, faces) for every edge, a < b, in increasing (a, b)
  template <class F> void forEach(F&& fn) const {
    for (std::size_t i = 0; i < keys_.size(); ++i)
      fn(int(keys_[i] >> 32), int(keys_[i] & 0xffffffffu), Faces{faces_.data() + start_[i], faces_.data() + start_[i + 1]});
  }
  std::size_t size() const { return keys_.size(); }

 private:
  static std::uint64_t key(int a, int b) {
    if (a > b) std::swap(a, b);
    return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
  }
  std::vector<std::uint64_t> keys_;  ///< distinct edges, ascending
  std::vector<int> start_;           ///< faces of edge i: faces_[start_[i] .. start_[i+1])
  std::vector<int> faces_;
};

}  // namespace pectus
