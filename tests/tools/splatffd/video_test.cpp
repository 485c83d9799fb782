// `splatffd render --video` through the built binary: MP4 and GIF of the same frames agree on the
// background (black without --background, the --background colour with it) and on the object.
// Skipped where ffmpeg is not installed (tools/bootstrap.sh installs it).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "tests/test_util/run_tool.h"

namespace fs = std::filesystem;

namespace {

constexpr int W = 96, H = 54;

fs::path temp_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_video_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

// The first frame of a video as W x H RGB bytes (decoded by ffmpeg); empty on failure.
std::vector<std::uint8_t> first_frame_rgb(const fs::path& video) {
    const fs::path raw = video.string() + ".rgb";
    if (sffd::test::run_shell("ffmpeg -nostdin -loglevel error -y -i " + video.string() +
                              " -frames:v 1 -vf crop=" + std::to_string(W) + ":" + std::to_string(H) +
                              ":0:0 -f rawvideo -pix_fmt rgb24 " + raw.string()) != 0)
        return {};
    std::ifstream in(raw, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

int channel(const std::vector<std::uint8_t>& rgb, int x, int y, int c) {
    return rgb[std::size_t((y * W + x) * 3 + c)];
}

double block_mean(const std::vector<std::uint8_t>& rgb, int c) {
    double sum = 0.0;
    for (int y = H / 2 - 6; y < H / 2 + 6; ++y)
        for (int x = W / 2 - 6; x < W / 2 + 6; ++x) sum += channel(rgb, x, y, c);
    return sum / 144.0;
}

// Renders two frames of the sphere into MP4 and GIF with the given extra options; returns both first frames.
void render_both(const std::string& extra, std::vector<std::uint8_t>& mp4, std::vector<std::uint8_t>& gif,
                 const std::string& name) {
    const fs::path dir = temp_dir(name);
    for (const char* ext : {"mp4", "gif"}) {
        const auto r = sffd::test::run_headless("render sphere --frames 2 --size " + std::to_string(W) + "x" +
                                                std::to_string(H) + " --format png --quality preview " +
                                                extra + " --out " + (dir / ext).string() + " --video " +
                                                (dir / (std::string("clip.") + ext)).string());
        ASSERT_EQ(r.code, 0) << r.out;
    }
    mp4 = first_frame_rgb(dir / "clip.mp4");
    gif = first_frame_rgb(dir / "clip.gif");
    ASSERT_EQ(mp4.size(), std::size_t(W * H * 3));
    ASSERT_EQ(gif.size(), std::size_t(W * H * 3));
}

}  // namespace

TEST(RenderVideo, Mp4AndGifAgreeOnTheBackgroundAndTheObject) {
    if (sffd::test::run_shell("command -v ffmpeg >/dev/null 2>&1") != 0)
        GTEST_SKIP() << "ffmpeg is not installed (tools/bootstrap.sh installs it)";
    std::vector<std::uint8_t> mp4, gif;
    render_both("", mp4, gif, "default");
    // Without --background both are over black (the GIF used to stay transparent, the MP4 black).
    for (int c = 0; c < 3; ++c) {
        EXPECT_LE(channel(mp4, 2, 2, c), 12) << "mp4 corner channel " << c;
        EXPECT_LE(channel(gif, 2, 2, c), 12) << "gif corner channel " << c;
    }
    // The object in the middle: the same colour up to H.264 (chroma at half resolution) and palette
    // dithering, so compared as the mean of a 12 x 12 block of the textured sphere, not pixel by pixel.
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(block_mean(mp4, c), block_mean(gif, c), 12.0) << "centre block channel " << c;
    EXPECT_GT(block_mean(mp4, 0) + block_mean(mp4, 1) + block_mean(mp4, 2), 60.0) << "the sphere is drawn";

    render_both("--background 1,1,1", mp4, gif, "white");
    for (int c = 0; c < 3; ++c) {
        EXPECT_GE(channel(mp4, 2, 2, c), 243) << "mp4 corner channel " << c;
        EXPECT_GE(channel(gif, 2, 2, c), 243) << "gif corner channel " << c;
    }
}

// An odd size: the MP4 is padded to even with the background colour, and the command says so; a GIF keeps
// the size and says nothing.
TEST(RenderVideo, OddSizeMp4IsPaddedWithTheBackgroundAndSaysSo) {
    if (sffd::test::run_shell("command -v ffmpeg >/dev/null 2>&1") != 0)
        GTEST_SKIP() << "ffmpeg is not installed (tools/bootstrap.sh installs it)";
    const fs::path dir = temp_dir("odd");
    const std::string common =
        "render sphere --frames 2 --size 61x31 --format png --quality preview "
        "--background 0,1,0 --out ";
    auto r =
        sffd::test::run_headless(common + (dir / "mp4").string() + " --video " + (dir / "odd.mp4").string());
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find(
                  "splatffd render: note: " + (dir / "odd.mp4").string() +
                  ": 61x31 padded to 62x32 with the background colour (H.264 needs an even width and height"),
              std::string::npos)
        << r.out;
    r = sffd::test::run_command(
        "ffprobe -v error -select_streams v:0 -show_entries stream=width,height -of csv=p=0 " +
        (dir / "odd.mp4").string());
    EXPECT_EQ(r.out, "62,32\n");
    // The padded column and row are the background (green), not black.
    const fs::path raw = dir / "odd.rgb";
    ASSERT_EQ(sffd::test::run_shell("ffmpeg -nostdin -loglevel error -y -i " + (dir / "odd.mp4").string() +
                                    " -frames:v 1 -f rawvideo -pix_fmt rgb24 " + raw.string()),
              0);
    std::ifstream in(raw, std::ios::binary);
    const std::vector<std::uint8_t> rgb{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    ASSERT_EQ(rgb.size(), std::size_t(62 * 32 * 3));
    for (const auto& [x, y] : {std::pair{61, 5}, std::pair{5, 31}, std::pair{61, 31}}) {
        const std::size_t at = std::size_t((y * 62 + x) * 3);
        EXPECT_LE(rgb[at], 40) << x << "," << y;
        EXPECT_GE(rgb[at + 1], 200) << x << "," << y;
    }
    r = sffd::test::run_headless(common + (dir / "gif").string() + " --video " + (dir / "odd.gif").string());
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(r.out.find("note:"), std::string::npos) << r.out;
}
