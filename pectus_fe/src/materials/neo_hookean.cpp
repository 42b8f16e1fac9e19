// FEBio's compressible neo-Hookean (Bonet & Wood): W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2.
#include <cmath>

#include "material.h"
#include "voigt.h"

namespace pectus::fe {

using Eigen::Matrix3d;

void neoHookeanResponse(double lam, double mu, double J, const Matrix3d& Ci, Matrix3d& S, Matrix6d& D) {
  const Matrix3d I = Matrix3d::Identity();
  // S = mu (I - C^-1) + lambda ln J C^-1; D = lambda C^-1 x C^-1 + 2 (mu - lambda ln J) dC^-1
  const double lnJ = std::log(J);
  S = mu * (I - Ci) + lam * lnJ * Ci;
  addDyad(D, lam, Ci, Ci);
  addSymProduct(D, 2 * (mu - lam * lnJ), Ci);
}

}  // namespace pectus::fe
