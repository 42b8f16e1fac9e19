#include "pectus/folds.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
#include <utility>

namespace pectus {

Vec3 elementNormal(const Element& e, const std::vector<Vec3>& X) {
  const auto p = [&](int k) { return X[std::size_t(e.v[std::size_t(k)])]; };
  const Vec3 n = e.nv == 3 ? Vec3((p(1) - p(0)).cross(p(2) - p(0))) : Vec3((p(2) - p(0)).cross(p(3) - p(1)));
  const double len = n.norm();
  return len > 0 && std::isfinite(len) ? Vec3(n / len) : Vec3::Zero();
}

Folds::Folds(std::vector<Element> elements, std::size_t nodes)
    : E_(std::move(elements)), nb_(E_.size()), vE_(nodes) {
  std::map<std::pair<int, int>, std::vector<int>> byEdge;
  for (int e = 0; e < int(E_.size()); ++e) {
    const Element& el = E_[std::size_t(e)];
    for (int k = 0; k < el.nv; ++k) {
      const int a = el.v[std::size_t(k)], b = el.v[std::size_t((k + 1) % el.nv)];
      assert(a >= 0 && std::size_t(a) < nodes && b >= 0 && std::size_t(b) < nodes);
      vE_[std::size_t(a)].push_back(e);
      byEdge[std::minmax(a, b)].push_back(e);
    }
  }
  for (const auto& [edge, es] : byEdge)
    for (int e : es)
      for (int g : es)
        if (g != e) nb_[std::size_t(e)].push_back(g);
  for (auto& n : nb_) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
}

bool Folds::folded(int e, const std::vector<Vec3>& X) const {
  return foldedBy(e, [&](int g) { return elementNormal(E_[std::size_t(g)], X); });
}

std::vector<Vec3> Folds::normals(const std::vector<Vec3>& X) const {
  std::vector<Vec3> n(E_.size());
#pragma omp parallel for schedule(static)
  for (int e = 0; e < int(E_.size()); ++e) n[std::size_t(e)] = elementNormal(E_[std::size_t(e)], X);
  return n;
}

std::vector<char> Folds::all(const std::vector<Vec3>& X) const {
  std::vector<char> f(E_.size(), 0);
#pragma omp parallel for schedule(static)
  for (int e = 0; e < int(E_.size()); ++e) f[std::size_t(e)] = folded(e, X);
  return f;
}

std::size_t Folds::count(const std::vector<Vec3>& X) const {
  const std::vector<char> f = all(X);
  return std::size_t(std::count(f.begin(), f.end(), char(1)));
}

void Folds::readers(int n, std::vector<int>& r) const {
  r.clear();
  for (int e : vE_[std::size_t(n)]) {
    r.push_back(e);
    r.insert(r.end(), nb_[std::size_t(e)].begin(), nb_[std::size_t(e)].end());
  }
  std::sort(r.begin(), r.end());
  r.erase(std::unique(r.begin(), r.end()), r.end());
}

}  // namespace pectus
