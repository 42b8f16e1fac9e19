// CalculiX's (and Abaqus') NEO HOOKE: W = C10 (I1bar - 3) + (J - 1)^2 / D1, C10 = mu / 2, D1 = 2 / K.
#include <cmath>

#include "material.h"
#include "voigt.h"

namespace pectus::fe {

using Eigen::Matrix3d;

void neoHookeanDecoupledResponse(const Material& m, double mu, double J, const Matrix3d& C, const Matrix3d& Ci,
                                 Matrix3d& S, Matrix6d& D) {
  const Matrix3d I = Matrix3d::Identity();
  // isochoric: S = mu J^(-2/3) (I - I1/3 C^-1), D = 2/3 mu J^(-2/3) [I1 dC^-1 + I1/3 C^-1 x C^-1 - I x C^-1 - C^-1 x I]
  // volumetric U = K/2 (J - 1)^2 (= (J - 1)^2 / D1): p = K (J - 1), S = J p C^-1,
  // D = J (p + J K) C^-1 x C^-1 - 2 J p dC^-1   (Holzapfel, Nonlinear Solid Mechanics, 6.4)
  const double K = m.E / (3 * (1 - 2 * m.nu)), I1 = C.trace(), j23 = std::pow(J, -2.0 / 3.0), p = K * (J - 1);
  S = mu * j23 * (I - I1 / 3 * Ci) + J * p * Ci;
  const double c = 2.0 / 3.0 * mu * j23;
  addSymProduct(D, c * I1 - 2 * J * p, Ci);
  addDyad(D, c * I1 / 3 + J * (p + J * K), Ci, Ci);
  addDyad(D, -c, I, Ci);
  addDyad(D, -c, Ci, I);
}

}  // namespace pectus::fe
