// The tetrahedral elements: quadrature, shape functions, the B matrix, the element tangent and internal
// forces, the stress at the centroid.
#include "element.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pectus::fe {

using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

const std::vector<Gauss>& rule(int order) {
  static const std::vector<Gauss> r1{{{0.25, 0.25, 0.25, 0.25}, 1.0 / 6.0}};
  static const double a = 0.5854101966249685, b = 0.1381966011250105;
  static const std::vector<Gauss> r2{{{a, b, b, b}, 1.0 / 24}, {{b, a, b, b}, 1.0 / 24},
                                     {{b, b, a, b}, 1.0 / 24}, {{b, b, b, a}, 1.0 / 24}};
  return order == 2 ? r2 : r1;
}

// derivatives of the shape functions w.r.t. (xi, eta, zeta) at volume coordinates L (L0 = 1-xi-eta-zeta)
void shapeDerivs(int order, const double L[4], Eigen::Matrix<double, 10, 3>& dN) {
  Eigen::Matrix<double, 10, 4> dL = Eigen::Matrix<double, 10, 4>::Zero();  // dN/dL_k
  if (order == 1) {
    for (int i = 0; i < 4; ++i) dL(i, i) = 1.0;
  } else {
    for (int i = 0; i < 4; ++i) dL(i, i) = 4.0 * L[i] - 1.0;
    for (int k = 0; k < 6; ++k) {
      int a = kTetEdges[k][0], b = kTetEdges[k][1];
      dL(4 + k, a) = 4.0 * L[b];
      dL(4 + k, b) = 4.0 * L[a];
    }
  }
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 3; ++j) dN(i, j) = dL(i, j + 1) - dL(i, 0);
}

inline Eigen::Matrix<double, 6, 1> voigt(const Matrix3d& s, bool engineeringShear) {
  const double f = engineeringShear ? 2.0 : 1.0;
  Eigen::Matrix<double, 6, 1> v;
  v << s(0, 0), s(1, 1), s(2, 2), f * s(0, 1), f * s(1, 2), f * s(0, 2);
  return v;
}

double vonMisesOf(const Matrix3d& s) {
  return std::sqrt(0.5 * ((s(0, 0) - s(1, 1)) * (s(0, 0) - s(1, 1)) + (s(1, 1) - s(2, 2)) * (s(1, 1) - s(2, 2)) +
                          (s(2, 2) - s(0, 0)) * (s(2, 2) - s(0, 0))) +
                   3.0 * (s(0, 1) * s(0, 1) + s(1, 2) * s(1, 2) + s(0, 2) * s(0, 2)));
}
// ANSYS EPEL,EQV: 1/(1+nu') sqrt(1/2 sum (ei-ej)^2 + 3/4 sum gamma^2), gamma engineering shear = 2 e_ij
double eqStrainOf(const Matrix3d& e, double nu) {
  const double g01 = 2 * e(0, 1), g12 = 2 * e(1, 2), g02 = 2 * e(0, 2);
  return std::sqrt(0.5 * ((e(0, 0) - e(1, 1)) * (e(0, 0) - e(1, 1)) + (e(1, 1) - e(2, 2)) * (e(1, 1) - e(2, 2)) +
                          (e(2, 2) - e(0, 0)) * (e(2, 2) - e(0, 0))) +
                   0.75 * (g01 * g01 + g12 * g12 + g02 * g02)) /
         (1.0 + nu);
}

// Hooke's matrix D times strain E, as a symmetric stress tensor
inline Matrix3d hookeStress(const Eigen::Matrix<double, 6, 6>& D, const Matrix3d& E) {
  const Eigen::Matrix<double, 6, 1> Sv = D * voigt(E, true);
  Matrix3d S;
  S << Sv(0), Sv(3), Sv(5), Sv(3), Sv(1), Sv(4), Sv(5), Sv(4), Sv(2);
  return S;
}

// the deformation gradient F (identity for small strain) and the stress S (second Piola-Kirchhoff; small
// strain: sigma) at displacement gradient H; a hyperelastic law gives its tangent in Dq
inline void stressAt(const Material& mat, const Eigen::Matrix<double, 6, 6>& D, const Matrix3d& H, bool nonlinear,
                     bool hyper, Matrix3d& F, Matrix3d& S, Eigen::Matrix<double, 6, 6>& Dq) {
  F = Matrix3d::Identity();
  if (hyper) {
    F += H;
    materialResponse(mat, F, S, Dq);  // NaN when inverted: the residual is not finite, Newton backs off
  } else {
    Matrix3d E;
    if (nonlinear) {
      F += H;
      E = 0.5 * (H + H.transpose() + H.transpose() * H);
    } else {
      E = 0.5 * (H + H.transpose());
    }
    S = hookeStress(D, E);
  }
}

// the strain-displacement matrix B (dE = B du, engineering shears) at F with gradients G
template <int NEN>
inline void strainDisplacement(const Matrix3d& F, const Eigen::Matrix<double, NEN, 3>& G,
                               Eigen::Matrix<double, 6, 3 * NEN>& B) {
  for (int a = 0; a < NEN; ++a) {
    const Vector3d Ga = G.row(a).transpose();
    for (int i = 0; i < 3; ++i) {
      B(0, 3 * a + i) = F(i, 0) * Ga(0);
      B(1, 3 * a + i) = F(i, 1) * Ga(1);
      B(2, 3 * a + i) = F(i, 2) * Ga(2);
      B(3, 3 * a + i) = F(i, 0) * Ga(1) + F(i, 1) * Ga(0);
      B(4, 3 * a + i) = F(i, 1) * Ga(2) + F(i, 2) * Ga(1);
      B(5, 3 * a + i) = F(i, 0) * Ga(2) + F(i, 2) * Ga(0);
    }
  }
}

// fe += w * P * G_a per node a (P: first Piola-Kirchhoff stress; small strain: sigma)
template <int NEN>
inline void addInternalForce(double w, const Matrix3d& P, const Eigen::Matrix<double, NEN, 3>& G,
                             Eigen::Matrix<double, 3 * NEN, 1>& fe) {
  for (int a = 0; a < NEN; ++a) {
    const Vector3d Ga = G.row(a).transpose();
    fe.template segment<3>(3 * a) += w * P * Ga;
  }
}

// Ke += w B^T Dm B, and for nonlinear kinematics the geometric stiffness w G S G^T on each direction
template <int NEN>
inline void addTangent(double w, const Eigen::Matrix<double, 6, 6>& Dm, const Matrix3d& F, const Matrix3d& S,
                       const Eigen::Matrix<double, NEN, 3>& G, bool nonlinear,
                       Eigen::Matrix<double, 3 * NEN, 3 * NEN>& Ke) {
  constexpr int ND = 3 * NEN;
  Eigen::Matrix<double, 6, ND> B;
  strainDisplacement<NEN>(F, G, B);
  const Eigen::Matrix<double, 6, ND> DB = (w * Dm) * B;
  Ke.noalias() += B.transpose().lazyProduct(DB);
  if (nonlinear) {
    const Eigen::Matrix<double, NEN, NEN> GSG = w * G * S * G.transpose();
    for (int a = 0; a < NEN; ++a)
      for (int b = 0; b < NEN; ++b)
        for (int i = 0; i < 3; ++i) Ke(3 * a + i, 3 * b + i) += GSG(a, b);
  }
}

// the tet's nodal displacements, one node per row
template <int NEN>
inline Eigen::Matrix<double, NEN, 3> nodalDisplacements(const TetMesh& m, int t, const Eigen::VectorXd& u) {
  Eigen::Matrix<double, NEN, 3> ue;
  for (int a = 0; a < NEN; ++a) ue.row(a) = u.template segment<3>(3 * m.tets[t][a]).transpose();
  return ue;
}

// det F of tet t at the point with reference derivatives dN
template <int NEN>
double detF(const TetMesh& m, int t, const Eigen::Matrix<double, 10, 3>& dN, const Eigen::VectorXd& u) {
  Matrix3d H = Matrix3d::Zero();
  Eigen::Matrix<double, NEN, 3> G;
  gradients<NEN>(m, t, dN, 1.0, G);
  for (int a = 0; a < NEN; ++a) H += u.segment<3>(3 * m.tets[t][a]) * G.row(a);
  return (Matrix3d::Identity() + H).determinant();
}

}  // namespace

void ReferenceTet::setOrder(int order) {
  quad = rule(order);
  quadDN.resize(quad.size());
  for (std::size_t q = 0; q < quad.size(); ++q) shapeDerivs(order, quad[q].L, quadDN[q]);
  const double c[4] = {0.25, 0.25, 0.25, 0.25};
  shapeDerivs(order, c, centroidDN);
}

template <int NEN>
void tetTangent(const TetMesh& m, int t, const ReferenceTet& ref, const Material& mat, const Eigen::Matrix<double, 6, 6>& D,
                const Eigen::VectorXd& u, bool nonlinear, bool tangent, Eigen::Matrix<double, 3 * NEN, 3 * NEN>& Ke,
                Eigen::Matrix<double, 3 * NEN, 1>& fe) {
  Ke.setZero();
  fe.setZero();
  Eigen::Matrix<double, NEN, 3> G;
  const Eigen::Matrix<double, NEN, 3> ue = nodalDisplacements<NEN>(m, t, u);
  const bool hyper = nonlinear && mat.model != MaterialModel::StVenantKirchhoff;
  Eigen::Matrix<double, 6, 6> Dq;  // the hyperelastic tangent at a quadrature point
  for (std::size_t q = 0; q < ref.quad.size(); ++q) {
    const double w = gradients<NEN>(m, t, ref.quadDN[q], ref.quad[q].w, G);
    const Matrix3d H = ue.transpose() * G;  // du_i/dX_j
    Matrix3d F, S;
    stressAt(mat, D, H, nonlinear, hyper, F, S, Dq);
    const auto& Dm = hyper ? Dq : D;
    const Matrix3d P = F * S;  // first Piola (linear: sigma)
    addInternalForce<NEN>(w, P, G, fe);
    if (tangent) addTangent<NEN>(w, Dm, F, S, G, nonlinear, Ke);
  }
}

template <int NEN>
void tetStress(const TetMesh& m, int t, const ReferenceTet& ref, const Material& mat, const Eigen::Matrix<double, 6, 6>& D,
               const Eigen::VectorXd& u, bool nonlinear, double& vonMises, double& eqStrain) {
  Eigen::Matrix<double, NEN, 3> G;
  const Eigen::Matrix<double, NEN, 3> ue = nodalDisplacements<NEN>(m, t, u);
  gradients<NEN>(m, t, ref.centroidDN, 1.0, G);
  const Matrix3d H = ue.transpose().lazyProduct(G);
  Matrix3d E = nonlinear ? Matrix3d(0.5 * (H + H.transpose() + H.transpose() * H)) : Matrix3d(0.5 * (H + H.transpose()));
  Matrix3d S;
  if (nonlinear && mat.model != MaterialModel::StVenantKirchhoff) {
    Eigen::Matrix<double, 6, 6> Dq;
    materialResponse(mat, Matrix3d::Identity() + H, S, Dq);
  } else {
    S = hookeStress(D, E);
  }
  if (nonlinear) {
    const Matrix3d F = Matrix3d::Identity() + H;
    S = F * S * F.transpose() / F.determinant();
  }
  vonMises = vonMisesOf(S);
  eqStrain = eqStrainOf(E, mat.nu);
}

double tetMinDetF(const TetMesh& m, int t, int nen, const ReferenceTet& ref, const Eigen::VectorXd& u) {
  double minJ = std::numeric_limits<double>::infinity();
  auto check = [&](const Eigen::Matrix<double, 10, 3>& dN) {
    minJ = std::min(minJ, nen == 10 ? detF<10>(m, t, dN, u) : detF<4>(m, t, dN, u));
  };
  check(ref.centroidDN);
  for (const auto& dN : ref.quadDN) check(dN);
  return minJ;
}

template void tetTangent<4>(const TetMesh&, int, const ReferenceTet&, const Material&, const Eigen::Matrix<double, 6, 6>&,
                            const Eigen::VectorXd&, bool, bool, Eigen::Matrix<double, 12, 12>&, Eigen::Matrix<double, 12, 1>&);
template void tetTangent<10>(const TetMesh&, int, const ReferenceTet&, const Material&, const Eigen::Matrix<double, 6, 6>&,
                             const Eigen::VectorXd&, bool, bool, Eigen::Matrix<double, 30, 30>&, Eigen::Matrix<double, 30, 1>&);
template void tetStress<4>(const TetMesh&, int, const ReferenceTet&, const Material&, const Eigen::Matrix<double, 6, 6>&,
                           const Eigen::VectorXd&, bool, double&, double&);
template void tetStress<10>(const TetMesh&, int, const ReferenceTet&, const Material&, const Eigen::Matrix<double, 6, 6>&,
                            const Eigen::VectorXd&, bool, double&, double&);

}  // namespace pectus::fe
