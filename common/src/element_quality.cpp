#include "pectus/element_quality.h"

namespace pectus {

double elementQuality(const Element& e, const std::vector<Vec3>& X) {
  const auto P = [&X](int i) -> const Vec3& { return X[std::size_t(i)]; };
  return e.nv == 4 ? quadBeta(P(e.v[0]), P(e.v[1]), P(e.v[2]), P(e.v[3])) : triangleAlpha(P(e.v[0]), P(e.v[1]), P(e.v[2]));
}

std::vector<double> elementQualities(const std::vector<Element>& elements, const std::vector<Vec3>& X) {
  std::vector<double> q(elements.size());
#pragma omp parallel for schedule(static)
  for (long i = 0; i < long(elements.size()); ++i) q[std::size_t(i)] = elementQuality(elements[std::size_t(i)], X);
  return q;
}

std::vector<double> spreadToFaces(const std::vector<Element>& elements, const std::vector<double>& perElement,
                                  std::size_t faceCount) {
  std::vector<double> perFace(faceCount, 0.0);
  for (std::size_t i = 0; i < elements.size(); ++i)
    for (int f : elements[i].face)
      if (f >= 0) perFace[std::size_t(f)] = perElement[i];
  return perFace;
}

ElementQuality computeElementQuality(const CMeshO& m, ElementKind kind, int histogramBins) {
  ElementQuality q;
  q.mesh = buildElements(m, kind);
  std::vector<Vec3> X(m.vert.size());
  for (std::size_t i = 0; i < m.vert.size(); ++i) X[i] = toEigen(m.vert[i].cP());
  q.perElement = elementQualities(q.mesh.elements, X);
  q.perFace = spreadToFaces(q.mesh.elements, q.perElement, m.face.size());
  q.stats = summarizeQuality(q.perElement, histogramBins);
  return q;
}

}  // namespace pectus
