// Fixture base for GL tests that need a current context and nothing else from a window: a 16 x 16 headless
// EGL context per test; where none can be made the test fails, or skips under SFFD_NO_GL=1
// (gl_required.h). Objects a derived fixture makes in SetUp() die before the context (derived members
// are destroyed before base ones).
#pragma once

#include <gtest/gtest.h>

#include <optional>
#include <utility>

#include "runtime/core/result.h"
#include "runtime/gfx/context.h"
#include "tests/test_util/gl_required.h"

namespace sffd::test {

class HeadlessGlTest : public testing::Test {
protected:
    // A derived SetUp() calls this first and returns when IsSkipped() || HasFatalFailure().
    void SetUp() override {
        auto c = gfx::create_context({.headless = true, .width = 16, .height = 16});
        if (!c) SFFD_GL_UNAVAILABLE(c.message());
        ctx.emplace(std::move(*c));
    }
    std::optional<gfx::GlContext> ctx;
};

template <class Param>
class HeadlessGlTestWithParam : public HeadlessGlTest, public testing::WithParamInterface<Param> {};

// Puts the made GL object in `slot`, or fails the test with the reason.
template <class T>
void emplace_made(std::optional<T>& slot, Result<T> made) {
    ASSERT_TRUE(made) << made.message();
    slot.emplace(std::move(*made));
}

}  // namespace sffd::test
