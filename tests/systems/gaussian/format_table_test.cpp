// Every command reads every Gaussian format (run as a user would: the built binary): info, render,
// convert, pick, profile and deform on a file of each format. Slow (six commands, ten formats).
#include <gtest/gtest.h>

#include "tests/systems/gaussian/format_files.h"

namespace {

using namespace sffd;
using namespace sffd::test::formats;

// The table: each command on each format. render draws the Gaussians (coverage), pick hits one, convert
// and deform write the file's count, profile runs its frames, info names the count.
TEST(FormatCommands, EveryCommandReadsEveryFormat) {
    const GaussianCloud g = shell(600);
    const fs::path lat = temp("table.json");
    save_bent_lattice(lat);
    for (const FormatFile& f : write_every_format(g)) {
        SCOPED_TRACE(f.format);
        const std::size_t n = f.format == ".ksplat" ? 3 : g.size();
        std::string in = "'";  // quoted: "'" + path + "'" trips GCC 12's -Wrestrict false positive
        in += f.path.string();
        in += '\'';
        RunResult r = run("info", in);
        EXPECT_EQ(r.code, 0) << r.err;
        EXPECT_NE(r.out.find(std::to_string(n) + " Gaussians"), std::string::npos) << r.out;

        r = run("convert", in + " " + temp("converted.ply").string() + " --gaussians");
        EXPECT_EQ(r.code, 0) << r.err;
        auto c = gaussian::read_ply(temp("converted.ply"));
        EXPECT_TRUE(c && c->size() == n) << (c ? std::to_string(c->size()) : c.message());

        r = run("deform", in + " " + temp("deformed.ply").string() + " --lattice fit");
        EXPECT_EQ(r.code, 0) << r.err;
        auto d = gaussian::read_ply(temp("deformed.ply"));
        EXPECT_TRUE(d && d->size() == n) << (d ? std::to_string(d->size()) : d.message());

        const fs::path frames = temp("render_" + std::to_string(std::hash<std::string>{}(f.format)));
        r = run("render", in + " --size 96x72 --out " + frames.string());
        if (r.code != 0 && r.err.find("EGL") != std::string::npos) SFFD_GL_UNAVAILABLE(r.err);
        EXPECT_EQ(r.code, 0) << r.err;
        auto png = render::read_png(frames / "frame_0000.png");
        ASSERT_TRUE(png) << png.message();
        std::size_t covered = 0;
        for (std::size_t p = 0; p < png->pixels.size() / 4; ++p) covered += png->pixels[p * 4 + 3] > 128;
        EXPECT_GT(covered, png->pixels.size() / 4 / 50) << "pixels drawn";

        r = run("pick", in + " --at 48,36 --size 96x72");
        EXPECT_EQ(r.code, 0) << r.err;
        EXPECT_NE(r.out.find("\"kind\":\"gaussian\""), std::string::npos) << r.out;

        r = run("profile", in + " --frames 1");
        EXPECT_EQ(r.code, 0) << r.err;
    }
}

}  // namespace
