// What a GL test does when it gets no GL: fail, because a run that should test GL and silently skips
// every GL test looks green while testing nothing. Only a run that says there is no GL on purpose
// (SFFD_NO_GL=1 in the environment, e.g. a CPU-only CI job) skips, with the reason.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <string_view>

namespace sffd::test {

inline bool gl_absent_on_purpose() {
    const char* v = std::getenv("SFFD_NO_GL");
    return v != nullptr && std::string_view(v) == "1";
}

}  // namespace sffd::test

// Use where a GL context (or a command that needs one) could not be made; `why` is streamed into the
// message. Returns from the calling function like GTEST_SKIP() / FAIL().
#define SFFD_GL_UNAVAILABLE(why)                                                                        \
    do {                                                                                                \
        if (::sffd::test::gl_absent_on_purpose()) GTEST_SKIP() << "SFFD_NO_GL=1: " << why;              \
        FAIL() << why << " (a GL test fails without GL; set SFFD_NO_GL=1 to skip GL tests on purpose)"; \
    } while (0)
