#include "pectus/element_quality.h"

namespace pectus {

ElementQuality computeElementQuality(const CMeshO& m, ElementKind kind, int histogramBins) {
  ElementQuality q;
  q.mesh = buildElements(m, kind);
  const auto P = [&m](int i) { return toEigen(m.vert[std::size_t(i)].cP()); };
  q.perElement.resize(q.mesh.elements.size());
#pragma omp parallel for schedule(static)
  for (long i = 0; i < long(q.mesh.elements.size()); ++i) {
    const Element& e = q.mesh.elements[std::size_t(i)];
    q.perElement[std::size_t(i)] = e.nv == 4 ? quadBeta(P(e.v[0]), P(e.v[1]), P(e.v[2]), P(e.v[3]))
                                             : triangleAlpha(P(e.v[0]), P(e.v[1]), P(e.v[2]));
  }
  q.perFace.assign(m.face.size(), 0.0);
  for (std::size_t i = 0; i < q.mesh.elements.size(); ++i)
    for (int f : q.mesh.elements[i].face)
      if (f >= 0) q.perFace[std::size_t(f)] = q.perElement[i];
  q.stats = summarizeQuality(q.perElement, histogramBins);
  return q;
}

}  // namespace pectus
