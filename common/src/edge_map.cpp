#include "pectus/edge_map.h"

namespace pectus {

EdgeMap::EdgeMap(const CMeshO& m) {
  map_.reserve(m.face.size() * 2);
  for (std::size_t fi = 0; fi < m.face.size(); ++fi) {
    const auto& f = m.face[fi];
    if (f.IsD()) continue;
    for (int k = 0; k < 3; ++k) {
      const int a = int(vcg::tri::Index(m, f.cV(k)));
      const int b = int(vcg::tri::Index(m, f.cV((k + 1) % 3)));
      map_[key(a, b)].push_back(int(fi));
    }
  }
}

const std::vector<int>& EdgeMap::faces(int a, int b) const {
  auto it = map_.find(key(a, b));
  return it == map_.end() ? empty_ : it->second;
}

}  // namespace pectus
