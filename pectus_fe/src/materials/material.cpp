// The materials' names, the thesis' materials, and materialResponse: the law of a material at F.
#include <cmath>
#include <limits>
#include <string>

#include "material.h"
#include "pectus/errors.h"

namespace pectus::fe {

using Eigen::Matrix3d;

std::map<int, Material> thesisMaterials(double nuBone, double nuCartilage, MaterialModel model, double eBone,
                                        double eCartilage) {
  return {{1, {eBone, nuBone, model}}, {2, {eCartilage, nuCartilage, model}}, {3, {eBone, nuBone, model}}};
}

const char* materialModelName(MaterialModel m) {
  switch (m) {
    case MaterialModel::NeoHookean: return "neo-hookean";
    case MaterialModel::NeoHookeanDecoupled: return "neo-hookean-ccx";
    default: return "svk";
  }
}

MaterialModel parseMaterialModel(const std::string& name) {
  for (MaterialModel m : {MaterialModel::StVenantKirchhoff, MaterialModel::NeoHookean, MaterialModel::NeoHookeanDecoupled})
    if (name == materialModelName(m)) return m;
  throw InputError("Unknown material model '" + name +
                   "': use svk (St Venant-Kirchhoff), neo-hookean (FEBio's compressible form) or neo-hookean-ccx "
                   "(CalculiX's NEO HOOKE, deviatoric/volumetric split).");
}

// the hyperelastic laws need J > 0 (their energy is infinite at an inverted state: S and D are NaN there)
double materialResponse(const Material& m, const Matrix3d& F, Matrix3d& S, Eigen::Matrix<double, 6, 6>& D) {
  const double lam = m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu)), mu = m.E / (2 * (1 + m.nu));
  const double J = F.determinant();
  D.setZero();
  if (m.model == MaterialModel::StVenantKirchhoff) {
    stVenantKirchhoffResponse(lam, mu, F, S, D);
    return J;
  }
  if (!(J > 0)) {
    S.setConstant(std::numeric_limits<double>::quiet_NaN());
    D.setConstant(std::numeric_limits<double>::quiet_NaN());
    return J;
  }
  const Matrix3d C = F.transpose() * F, Ci = C.inverse();
  if (m.model == MaterialModel::NeoHookean)
    neoHookeanResponse(lam, mu, J, Ci, S, D);
  else
    neoHookeanDecoupledResponse(m, mu, J, C, Ci, S, D);
  return J;
}

}  // namespace pectus::fe
