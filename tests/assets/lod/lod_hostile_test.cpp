// The streamed SOG reader's budgets with hostile files (streamed_sog.h): lod-meta.json truncated at every
// sixteenth of its length, hostile counts, offsets and levels, unit meta.json counts past the limit and
// past the texel-per-byte ratio, a manifest over its size budget, JSON nested too deep, and folder
// confinement: unit paths and image names that leave the folder, through "..", absolute paths or
// symlinks. Every refusal names the file; nothing is decoded before the whole hierarchy is checked.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "runtime/assets/formats/lod/lod_build.h"
#include "runtime/assets/formats/lod/streamed_sog.h"

namespace fs = std::filesystem;
using namespace sffd;

namespace {

void write_text(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }
std::string read_text(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

class LodHostile : public ::testing::Test {
protected:
    void SetUp() override {
        root_ = fs::temp_directory_path() / ("sffd_lod_hostile_" + std::to_string(::getpid()));
        fs::remove_all(root_);
        dir_ = root_ / "h";
        lod::LodBuildOptions o;
        o.levels = 2, o.chunk_count = 2048;
        ASSERT_TRUE(lod::build_streamed_sog(lod::synthetic_gaussian_source(5000), meta(), o));
        good_ = read_text(meta());
        unit_ = read_text(dir_ / "0_0" / "meta.json");
        ASSERT_TRUE(lod::open_streamed_sog(meta()));
    }
    void TearDown() override { fs::remove_all(root_); }

    fs::path meta() const { return dir_ / "lod-meta.json"; }
    std::string replaced(std::string text, const std::string& from, const std::string& to) const {
        const auto at = text.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        return at == std::string::npos ? text : text.replace(at, from.size(), to);
    }
    // open_streamed_sog refuses, naming `file` and saying `why`.
    void refused(const fs::path& file, const std::string& why) {
        auto s = lod::open_streamed_sog(meta());
        ASSERT_FALSE(s) << why;
        EXPECT_NE(s.message().find(file.filename().string()), std::string::npos) << s.message();
        EXPECT_NE(s.message().find(why), std::string::npos) << s.message();
    }
    void manifest(const std::string& text, const std::string& why) {
        write_text(meta(), text);
        refused(meta(), why);
        write_text(meta(), good_);
    }

    fs::path root_, dir_;
    std::string good_, unit_;
};

TEST_F(LodHostile, TruncatedManifestsAreRefused) {
    for (int k = 0; k < 16; ++k) manifest(good_.substr(0, good_.size() * std::size_t(k) / 16), "JSON");
    manifest(good_.substr(0, good_.size() - 1), "JSON");
}

TEST_F(LodHostile, HostileCountsOffsetsAndLevels) {
    manifest(replaced(good_, "\"offset\":0", "\"offset\":9007199254740991"), "0_0/meta.json");
    manifest(replaced(good_, "\"offset\":0", "\"offset\":18446744073709551615"), "offset and count");
    manifest(replaced(good_, "\"offset\":0", "\"offset\":-1"), "offset and count");
    manifest(replaced(good_, "\"offset\":0", "\"offset\":0.5"), "offset and count");
    manifest(replaced(good_, "\"offset\":0", "\"offset\":\"0\""), "offset and count");
    manifest(replaced(good_, "\"count\":", "\"count\":1e300,\"x\":"), "count");
    manifest(replaced(good_, "\"counts\":[", "\"counts\":[1,"), "counts");
    manifest(replaced(good_, "\"lodLevels\":2", "\"lodLevels\":33"), "lodLevels");
    manifest(replaced(good_, "\"lodLevels\":2", "\"lodLevels\":0"), "lodLevels");
    manifest(replaced(good_, "\"lods\":{\"0\"", "\"lods\":{\"7\""), "not a level below lodLevels");
    manifest(replaced(good_, "\"lods\":{\"0\"", "\"lods\":{\"00\""), "not a level below lodLevels");
    manifest(replaced(good_, "\"file\":0", "\"file\":4294967296"), "not an index");
    manifest(replaced(good_, "\"version\":1", "\"version\":2"), "version");
    manifest(replaced(good_, "\"min\":[", "\"min\":[null,"), "bound");
    manifest(replaced(good_, "\"min\":[", "\"max\":[0,0,0],\"min\":[1e30,"), "bound");
    // A run moved back by one onto the run before it in its unit.
    std::string overlap = good_;
    for (auto at = overlap.find("\"offset\":"); at != std::string::npos;
         at = overlap.find("\"offset\":", at + 1)) {
        const auto end = overlap.find_first_of(",}", at);
        const long off = std::stol(overlap.substr(at + 9, end - at - 9));
        if (off == 0) continue;
        overlap.replace(at + 9, end - at - 9, std::to_string(off - 1));
        break;
    }
    ASSERT_NE(overlap, good_);
    manifest(overlap, "runs overlap");
    // Nested past the JSON depth budget.
    manifest("{\"tree\":" + std::string(100000, '[') + std::string(100000, ']') + "}", "nesting");
}

TEST_F(LodHostile, UnitCountsPastTheLimitAndTheRatio) {
    // A unit that declares more Gaussians than one cloud may hold, or than its images could encode.
    const auto at = unit_.find("\"count\":");
    ASSERT_NE(at, std::string::npos);
    const auto end = unit_.find_first_of(",}", at);
    const auto with_count = [&](const std::string& c) {
        std::string u = unit_;
        return u.replace(at, end - at, "\"count\":" + c);
    };
    const fs::path unit = dir_ / "0_0" / "meta.json";
    write_text(unit, with_count("1099511627776"));
    refused(unit, "limit");
    write_text(unit, with_count("-3"));
    refused(unit, "count");
    write_text(unit, unit_.substr(0, unit_.size() / 3));
    refused(unit, "JSON");
    // A million Gaussians in images of a few bytes: past the texel-per-byte ratio, refused before decoding.
    write_text(unit, unit_);
    fs::copy(dir_ / "0_0", root_ / "images", fs::copy_options::recursive);
    for (const auto& e : fs::directory_iterator(dir_ / "0_0"))
        if (e.path().extension() == ".webp") write_text(e.path(), "RIFF0000");
    write_text(unit, with_count("1000000"));
    refused(unit, "a byte");
    write_text(unit, unit_);
    for (const auto& e : fs::directory_iterator(root_ / "images"))
        fs::copy_file(e.path(), dir_ / "0_0" / e.path().filename(), fs::copy_options::overwrite_existing);
    // A manifest over its byte budget is refused before it is read (a sparse file: no disk is used).
    { std::ofstream f(meta(), std::ios::binary | std::ios::trunc); }
    fs::resize_file(meta(), lod::kMaxLodMetaBytes + 1);
    refused(meta(), "limit");
    write_text(meta(), good_);
    auto s = lod::open_streamed_sog(meta());
    ASSERT_TRUE(s) << s.message();
    EXPECT_TRUE(lod::read_level(*s, 0));
}

TEST_F(LodHostile, PathsCannotLeaveTheFolder) {
    // Units named out of the folder.
    fs::create_directories(root_ / "outside");
    fs::copy(dir_ / "0_0", root_ / "outside" / "0_0", fs::copy_options::recursive);
    manifest(replaced(good_, "\"0_0/meta.json\"", "\"../outside/0_0/meta.json\""), "relative path");
    manifest(replaced(good_, "\"0_0/meta.json\"", "\"0_0/../../outside/0_0/meta.json\""), "relative path");
    manifest(replaced(good_, "\"0_0/meta.json\"", "\"" + (root_ / "outside/0_0/meta.json").string() + "\""),
             "relative path");
    manifest(replaced(good_, "\"0_0/meta.json\"", "\"0_0\\\\meta.json\""), "relative path");
    manifest(replaced(good_, "\"0_0/meta.json\"", "\"0_0/means_l.webp\""), "relative path");
    // A unit folder that is a symlink out of the folder.
    fs::create_directory_symlink(root_ / "outside" / "0_0", dir_ / "link");
    manifest(replaced(good_, "\"0_0/meta.json\"", "\"link/meta.json\""), "outside");
    // An image name that leaves the unit, and an image that is a symlink out of the folder.
    const auto image = unit_.find("means_l.webp");
    ASSERT_NE(image, std::string::npos);
    std::string u = unit_;
    write_text(dir_ / "0_0" / "meta.json", u.replace(image, 12, "../1_0/means_l.webp"));
    refused(dir_ / "0_0" / "meta.json", "plain file name");
    write_text(dir_ / "0_0" / "meta.json", unit_);
    fs::remove(dir_ / "0_0" / "means_l.webp");
    fs::create_symlink(root_ / "outside" / "0_0" / "means_l.webp", dir_ / "0_0" / "means_l.webp");
    refused(meta(), "outside");
    // The same symlink inside the folder is fine.
    fs::remove(dir_ / "0_0" / "means_l.webp");
    fs::copy_file(root_ / "outside" / "0_0" / "means_l.webp", dir_ / "spare.webp");
    fs::create_symlink(dir_ / "spare.webp", dir_ / "0_0" / "means_l.webp");
    auto s = lod::open_streamed_sog(meta());
    ASSERT_TRUE(s) << s.message();
    EXPECT_TRUE(lod::read_level(*s, 0));
    // Listed twice, or one unit for two levels.
    manifest(replaced(good_, "\"1_0/meta.json\"", "\"0_0/meta.json\""), "listed twice");
}

}  // namespace
