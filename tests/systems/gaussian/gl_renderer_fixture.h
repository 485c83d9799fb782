// A headless GL context and a gaussian::GlRenderer made in it, per test (failed, or skipped under
// SFFD_NO_GL=1, where no context can be made): the fixture of the Gaussian GL renderer tests, plain
// (`Base` = test::HeadlessGlTest) or parameterised (test::HeadlessGlTestWithParam<P>).
#pragma once

#include <optional>

#include "systems/gaussian/gl_render.h"
#include "tests/test_util/headless_gl.h"

namespace sffd::test {

template <class Base>
class GaussianGlRendererTest : public Base {
protected:
    void SetUp() override {
        Base::SetUp();
        if (this->IsSkipped() || this->HasFatalFailure()) return;
        emplace_made(renderer, gaussian::create_gl_renderer());
    }
    void TearDown() override { renderer.reset(); }
    std::optional<gaussian::GlRenderer> renderer;
};

}  // namespace sffd::test
