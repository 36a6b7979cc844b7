#pragma once
// Misuse checks shared by the suites: `call()` must throw E (a softhd::Error subclass)
// whose message contains `needle`.

#include <gtest/gtest.h>

#include <exception>
#include <string>

#include "softhd/error.hpp"

namespace softhd::test {

template <class E, class F>
void expect_error(F&& call, const std::string& needle) {
  try {
    call();
    ADD_FAILURE() << "no exception; expected one mentioning '" << needle << "'";
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "message: " << e.what() << "\nexpected to contain: " << needle;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

}  // namespace softhd::test
