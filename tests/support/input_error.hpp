// The message of the clothbake::Error(ExitCode::Input) that `f` throws, for tests of refusals: a
// failure is recorded when `f` throws nothing or an error of another kind.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "common/error.hpp"

namespace clothbake::test_support {

inline std::string input_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Input) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

}  // namespace clothbake::test_support
