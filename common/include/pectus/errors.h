#pragma once
#include <stdexcept>
#include <string>

// The errors the pectus cores throw on purpose. Every message is complete as it stands: the adapters and the
// command-line tools print what() unchanged, so the kind only tells a caller what went wrong, never adds text.
//
//   std::runtime_error
//   ├─ InputError            bad input or parameters; the message names what to fix
//   │  ├─ TopologyError      the mesh is not what the algorithm needs (open, non-manifold, self-intersecting...)
//   │  ├─ SolverFailure      a numerical method could not finish (singular, not converging, over budget...)
//   │  └─ IOError            a file cannot be opened, read, parsed or written
//   └─ InternalError         a core's own check failed: a precondition its caller should have ensured, or an
//                            algorithm that did not reach its result on input it accepted
//
// The three specific kinds derive from InputError, so `catch (const InputError&)` catches all four; a caller that
// can act on one kind (retry a solve, try another file) catches that kind first. InternalError is no InputError:
// the adapter base (common/meshlab/filter_plugin.cpp) logs it as "internal error: <what>", like any other
// std::exception.

namespace pectus {
/// Bad input or parameters: the message is written for the user (it names what to fix).
/// What to do: change the parameter or the input the message names, and run again.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

/// The mesh is not what the algorithm needs: no faces, open, non-manifold, self-intersecting, disconnected,
/// degenerate faces, elements that are not the expected polygons, or a surface TetGen cannot mesh.
/// What to do: repair the mesh as the message says (close holes, remove duplicate or self-intersecting faces,
/// split components into layers) or choose a mesh that has the required shape.
class TopologyError : public InputError {
 public:
  using InputError::InputError;
};

/// A numerical method could not finish: a singular or indefinite stiffness matrix, Newton not converging, an
/// element inverted by the load, a fit without a solution, or a model over the memory or time budget.
/// What to do: follow the message (smaller load or step, coarser mesh, other material or boundary
/// conditions); the input itself was accepted.
class SolverFailure : public InputError {
 public:
  using InputError::InputError;
};

/// A file cannot be opened, read, parsed or written; the message names the file and the problem.
/// What to do: check the path, the permissions and the file's format and contents.
class IOError : public InputError {
 public:
  using InputError::InputError;
};

/// A core's own check failed: a precondition its caller should have ensured (a parameter the adapter already
/// range-checks), or an algorithm that did not reach its result on input it accepted. It is a limitation or a
/// bug of the core, not something the input's author can fix from the message alone.
/// What to do: report it with the input and the parameters; the adapters log it as "internal error: ...".
class InternalError : public std::runtime_error {
 public:
  explicit InternalError(const std::string& what) : std::runtime_error(what) {}
};
}  // namespace pectus
