// Test fixture shared by the Nuss analysis and bar planner tests: the coarse generated rib cage (6 mm edges,
// 12 rib pairs, built once per test binary) and the message of the InputError a call throws.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "pectus/errors.h"
#include "pectus/labels.h"
#include "pectus/ribcage/ribcage.h"

namespace pectus::fixture {

struct CoarseCage {
  OwnedMesh mesh;  // frees its face labels at exit (LeakSanitizer)
  std::vector<Landmark> lms;
  ribcage::RibCageStats stats;
};

inline CoarseCage& coarseCage() {
  static CoarseCage c;
  if (c.mesh.fn == 0) {
    ribcage::RibCageParams p;
    p.edgeLength = 6.0;
    p.ribPairs = 12;
    c.lms = ribcage::generateRibCage(p, c.mesh, &c.stats);
  }
  return c;
}

/// the message of the InputError f throws ("" when it throws none)
inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace pectus::fixture
