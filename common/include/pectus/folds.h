// Folds of a surface mesh: an element whose normal points against the mean of its edge neighbours' unit
// normals (n_e . sum_g n_g < 0, g over the elements that share an edge with e). A triangle's normal is its
// cross product, a quad's the cross product of its diagonals. Degenerate elements (no normal) and elements
// whose neighbours' normals cancel are not folds. The definition the smoothers' Log and
// bench/mga_smooth.py count by.
#pragma once
#include <cstddef>
#include <vector>

#include "pectus/elements.h"
#include "pectus/quality.h"

namespace pectus {

class Folds {
 public:
  /// the elements (copied) and the edge neighbours of each; their nodes are in [0, nodes)
  Folds(std::vector<Element> elements, std::size_t nodes);

  /// whether element e is folded with the nodes at X
  bool folded(int e, const std::vector<Vec3>& X) const;
  /// whether element e is folded, given each element's unit normal as normal(g) (e.g. kept up to date by a
  /// caller that moves one node at a time)
  template <class Normal>
  bool foldedBy(int e, const Normal& normal) const {
    Vec3 mean = Vec3::Zero();
    for (int g : nb_[std::size_t(e)]) mean += normal(g);
    return normal(e).dot(mean) < 0;
  }
  /// every element's unit normal at X (elementNormal)
  std::vector<Vec3> normals(const std::vector<Vec3>& X) const;
  /// per element, 1 if folded (in parallel; the same for any thread count)
  std::vector<char> all(const std::vector<Vec3>& X) const;
  std::size_t count(const std::vector<Vec3>& X) const;
  /// the elements whose fold test reads node n: its elements and their edge neighbours (sorted, into out)
  void readers(int n, std::vector<int>& out) const;
  /// element e's edge neighbours
  const std::vector<int>& neighbours(int e) const { return nb_[std::size_t(e)]; }
  const Element& element(int e) const { return E_[std::size_t(e)]; }

 private:
  std::vector<Element> E_;
  std::vector<std::vector<int>> nb_, vE_;
};

/// unit normal of an element (a quad: of its diagonals' cross product); zero if degenerate
Vec3 elementNormal(const Element& e, const std::vector<Vec3>& X);

}  // namespace pectus
