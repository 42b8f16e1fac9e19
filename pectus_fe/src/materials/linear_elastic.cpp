// Hooke's law, isotropic: the small-strain solve's material, with Lamé's lambda and mu from E and nu.
#include "material.h"

namespace pectus::fe {

Matrix6d linearElasticity(const Material& m) {
  const double lam = m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu)), mu = m.E / (2 * (1 + m.nu));
  Matrix6d D = Matrix6d::Zero();
  D.topLeftCorner<3, 3>().setConstant(lam);
  for (int i = 0; i < 3; ++i) D(i, i) += 2 * mu, D(3 + i, 3 + i) = mu;
  return D;
}

}  // namespace pectus::fe
