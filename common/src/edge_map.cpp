#include "pectus/edge_map.h"

#include <algorithm>
#include <utility>

namespace pectus {

EdgeMap::EdgeMap(const CMeshO& m) {
  std::vector<std::pair<std::uint64_t, int>> kf;
  kf.reserve(m.face.size() * 3);
  for (std::size_t fi = 0; fi < m.face.size(); ++fi) {
    const auto& f = m.face[fi];
    if (f.IsD()) continue;
    for (int k = 0; k < 3; ++k) {
      const int a = int(vcg::tri::Index(m, f.cV(k)));
      const int b = int(vcg::tri::Index(m, f.cV((k + 1) % 3)));
      kf.push_back({key(a, b), int(fi)});
    }
  }
  std::sort(kf.begin(), kf.end());
  faces_.resize(kf.size());
  for (std::size_t i = 0; i < kf.size(); ++i) {
    if (i == 0 || kf[i].first != kf[i - 1].first) {
      keys_.push_back(kf[i].first);
      start_.push_back(int(i));
    }
    faces_[i] = kf[i].second;
  }
  start_.push_back(int(kf.size()));
}

EdgeMap::Faces EdgeMap::faces(int a, int b) const {
  const std::uint64_t k = key(a, b);
  const auto it = std::lower_bound(keys_.begin(), keys_.end(), k);
  if (it == keys_.end() || *it != k) return {};
  const std::size_t i = std::size_t(it - keys_.begin());
  return {faces_.data() + start_[i], faces_.data() + start_[i + 1]};
}

}  // namespace pectus
