// The tetrahedral elements (TET4, TET10; C3D4/C3D10 node order): quadrature, shape function derivatives,
// gradients in the reference configuration, and the per-tet kernels of the assembly and the stresses.
#pragma once
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "pectus/fe/solver.h"
#include "pectus/fe/tet_mesh.h"

namespace pectus::fe {

struct Gauss { double L[4]; double w; };  ///< a quadrature point in volume coordinates, and its weight

/// The reference element of an order (1: TET4, 2: TET10): its quadrature rule, the shape derivatives at its
/// points, and at the centroid (where the stresses are taken)
struct ReferenceTet {
  std::vector<Gauss> quad;
  std::vector<Eigen::Matrix<double, 10, 3>> quadDN;
  Eigen::Matrix<double, 10, 3> centroidDN;
  void setOrder(int order);
};

/// the element gradients dN/dX of tet t at a point with reference derivatives dN10 (shapeDerivs); returns
/// det(J) * w. Fixed sizes throughout: a dynamic topRows(nen) product would go through Eigen's blocked GEMM kernel.
template <int NEN>
inline double gradients(const TetMesh& m, int t, const Eigen::Matrix<double, 10, 3>& dN10, double w,
                        Eigen::Matrix<double, NEN, 3>& G) {
  const Eigen::Matrix<double, NEN, 3> dN = dN10.template topRows<NEN>();
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  for (int a = 0; a < NEN; ++a) J.noalias() += m.nodes[m.tets[t][a]] * dN.row(a);
  const double det = J.determinant();
  G.noalias() = dN.lazyProduct(J.inverse());
  return det * w;
}

/// tet t's tangent Ke (tangent = true) and internal forces fe (zero on entry) at displacement u: the
/// small-strain stiffness (nonlinear = false), or the total-Lagrangian one with material mat (St
/// Venant-Kirchhoff: Hooke's matrix D)
template <int NEN>
void tetTangent(const TetMesh& m, int t, const ReferenceTet& ref, const Material& mat, const Eigen::Matrix<double, 6, 6>& D,
                const Eigen::VectorXd& u, bool nonlinear, bool tangent, Eigen::Matrix<double, 3 * NEN, 3 * NEN>& Ke,
                Eigen::Matrix<double, 3 * NEN, 1>& fe);

/// tet t's von Mises stress (Cauchy for nonlinear) and equivalent strain at its centroid
template <int NEN>
void tetStress(const TetMesh& m, int t, const ReferenceTet& ref, const Material& mat, const Eigen::Matrix<double, 6, 6>& D,
               const Eigen::VectorXd& u, bool nonlinear, double& vonMises, double& eqStrain);

/// min det F of tet t (nen nodes) over its centroid and quadrature points at displacement u
double tetMinDetF(const TetMesh& m, int t, int nen, const ReferenceTet& ref, const Eigen::VectorXd& u);

}  // namespace pectus::fe
