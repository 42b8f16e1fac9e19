// Disjoint sets of the integers 0..n-1 (union-find with path halving): connected pieces of meshes, grids and
// tet meshes. unite(a, b) hangs a's root under b's root, so which element ends as a set's root depends only
// on the order of the unions (the callers number pieces by their roots).
#pragma once
#include <cstddef>
#include <numeric>
#include <vector>

namespace pectus {

class UnionFind {
 public:
  explicit UnionFind(std::size_t n = 0) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  /// one more element, alone in its set; returns it
  int add() {
    parent_.push_back(int(parent_.size()));
    return parent_.back();
  }
  std::size_t size() const { return parent_.size(); }
  /// no elements (the storage is kept for the next use)
  void clear() { parent_.clear(); }
  /// the root of a's set
  int find(int a) {
    while (parent_[std::size_t(a)] != a) a = parent_[std::size_t(a)] = parent_[std::size_t(parent_[std::size_t(a)])];
    return a;
  }
  /// joins a's set to b's: b's root becomes the root of both
  void unite(int a, int b) {
    const int rb = find(b);
    parent_[std::size_t(find(a))] = rb;
  }
  bool isRoot(int a) const { return parent_[std::size_t(a)] == a; }

 private:
  std::vector<int> parent_;
};

}  // namespace pectus
