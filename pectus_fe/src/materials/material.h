// The constitutive laws behind materialResponse (solver.h), one unit each, and Hooke's matrix of the linear
// solve. Stresses are second Piola-Kirchhoff, tangents D = 2 dS/dC in Voigt order 00, 11, 22, 01, 12, 02.
#pragma once
#include <Eigen/Core>

#include "pectus/fe/solver.h"

namespace pectus::fe {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Hooke's law in Voigt form (engineering shears): the linear solve's matrix, and the St Venant-Kirchhoff tangent
Matrix6d linearElasticity(const Material& m);

/// St Venant-Kirchhoff at deformation gradient F (Lamé's lam, mu): S linear in the Green-Lagrange strain;
/// D is zero on entry
void stVenantKirchhoffResponse(double lam, double mu, const Eigen::Matrix3d& F, Eigen::Matrix3d& S, Matrix6d& D);

/// FEBio's compressible neo-Hookean at J = det F > 0, C^-1 = Ci; D is zero on entry
void neoHookeanResponse(double lam, double mu, double J, const Eigen::Matrix3d& Ci, Eigen::Matrix3d& S, Matrix6d& D);

/// CalculiX's NEO HOOKE (isochoric and volumetric parts) at J = det F > 0, C = F^T F, Ci = C^-1; D is zero on entry
void neoHookeanDecoupledResponse(const Material& m, double mu, double J, const Eigen::Matrix3d& C,
                                 const Eigen::Matrix3d& Ci, Eigen::Matrix3d& S, Matrix6d& D);

}  // namespace pectus::fe
