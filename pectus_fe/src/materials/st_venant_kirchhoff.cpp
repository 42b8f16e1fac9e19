// St Venant-Kirchhoff: W = lambda/2 (tr E)^2 + mu E:E, S = lambda tr E I + 2 mu E, D constant (Hooke's matrix).
#include "material.h"

namespace pectus::fe {

using Eigen::Matrix3d;

void stVenantKirchhoffResponse(double lam, double mu, const Matrix3d& F, Matrix3d& S, Matrix6d& D) {
  D.topLeftCorner<3, 3>().setConstant(lam);
  for (int i = 0; i < 3; ++i) D(i, i) += 2 * mu, D(3 + i, 3 + i) = mu;
  const Matrix3d E = 0.5 * (F.transpose() * F - Matrix3d::Identity());
  S = lam * E.trace() * Matrix3d::Identity() + 2 * mu * E;
}

}  // namespace pectus::fe
