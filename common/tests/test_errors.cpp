// The error kinds of pectus/errors.h: each specific kind is an InputError (so every catch of InputError, the
// adapter base's first, catches it) and a std::runtime_error; InternalError is neither an InputError nor a
// logic_error; what() is the message as given, byte for byte.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <type_traits>

#include "pectus/errors.h"

using namespace pectus;

static_assert(std::is_base_of_v<std::runtime_error, InputError>);
static_assert(std::is_base_of_v<InputError, TopologyError>);
static_assert(std::is_base_of_v<InputError, SolverFailure>);
static_assert(std::is_base_of_v<InputError, IOError>);
static_assert(std::is_base_of_v<std::runtime_error, InternalError>);
static_assert(!std::is_base_of_v<InputError, InternalError>);

namespace {
const std::string kMessage = "layer 'cage': the surface is open (12 boundary edges); a closed (watertight) surface is needed";

// What the adapter base logs for an exception (common/meshlab/filter_plugin.cpp, runFilter), without MeshLab.
template <class E>
std::string adapterFailure(const std::string& what) {
  try {
    throw E(what);
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::bad_alloc&) {
    return "out of memory";
  } catch (const std::exception& e) {
    return std::string("internal error: ") + e.what();
  } catch (...) {
    return "unknown internal error";
  }
}

template <class E>
void expectInputError() {
  try {
    throw E(kMessage);
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), kMessage);
  } catch (...) {
    ADD_FAILURE() << "not caught as InputError";
  }
  try {
    throw E(kMessage);
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), kMessage);
  } catch (...) {
    ADD_FAILURE() << "not caught as std::runtime_error";
  }
  EXPECT_EQ(adapterFailure<E>(kMessage), kMessage);
}
}  // namespace

TEST(Errors, InputErrorKeepsItsMessage) { expectInputError<InputError>(); }
TEST(Errors, TopologyErrorIsAnInputError) { expectInputError<TopologyError>(); }
TEST(Errors, SolverFailureIsAnInputError) { expectInputError<SolverFailure>(); }
TEST(Errors, IOErrorIsAnInputError) { expectInputError<IOError>(); }

TEST(Errors, EachKindIsCaughtAsItselfFirst) {
  auto kindOf = [](auto thrower) -> std::string {
    try {
      thrower();
    } catch (const TopologyError&) {
      return "topology";
    } catch (const SolverFailure&) {
      return "solver";
    } catch (const IOError&) {
      return "io";
    } catch (const InputError&) {
      return "input";
    } catch (const InternalError&) {
      return "internal";
    }
    return "none";
  };
  EXPECT_EQ(kindOf([] { throw TopologyError("t"); }), "topology");
  EXPECT_EQ(kindOf([] { throw SolverFailure("s"); }), "solver");
  EXPECT_EQ(kindOf([] { throw IOError("i"); }), "io");
  EXPECT_EQ(kindOf([] { throw InputError("u"); }), "input");
  EXPECT_EQ(kindOf([] { throw InternalError("b"); }), "internal");
}

TEST(Errors, InternalErrorIsLoggedAsAnInternalError) {
  const std::string m = "the decimated surface intersects itself (4 faces); use another edge length";
  try {
    throw InternalError(m);
  } catch (const InputError&) {
    ADD_FAILURE() << "an InternalError must not be caught as InputError";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), m);
  }
  EXPECT_EQ(adapterFailure<InternalError>(m), "internal error: " + m);
}

TEST(Errors, EmptyAndLongMessagesAreUnchanged) {
  EXPECT_EQ(std::string(TopologyError("").what()), "");
  const std::string longMessage(5000, 'x');
  EXPECT_EQ(std::string(SolverFailure(longMessage).what()), longMessage);
  EXPECT_EQ(std::string(IOError("cannot open file 'a b.stl'").what()), "cannot open file 'a b.stl'");
}
