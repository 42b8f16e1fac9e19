// Fourth-order tensor products in Voigt form (pairs 00, 11, 22, 01, 12, 02), for the hyperelastic tangents.
#pragma once
#include <Eigen/Core>

namespace pectus::fe {

// D(a, b) += s * (A_IJ B_KL) over Voigt pairs a = (IJ), b = (KL)
inline void addDyad(Eigen::Matrix<double, 6, 6>& D, double s, const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  static const int I[6] = {0, 1, 2, 0, 1, 0}, J[6] = {0, 1, 2, 1, 2, 2};
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) D(a, b) += s * A(I[a], J[a]) * B(I[b], J[b]);
}

// D(a, b) += s * 1/2 (A_IK A_JL + A_IL A_JK); with A = C^-1 this is -d(C^-1)/dC
inline void addSymProduct(Eigen::Matrix<double, 6, 6>& D, double s, const Eigen::Matrix3d& A) {
  static const int I[6] = {0, 1, 2, 0, 1, 0}, J[6] = {0, 1, 2, 1, 2, 2};
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b)
      D(a, b) += s * 0.5 * (A(I[a], I[b]) * A(J[a], J[b]) + A(I[a], J[b]) * A(J[a], I[b]));
}

}  // namespace pectus::fe
