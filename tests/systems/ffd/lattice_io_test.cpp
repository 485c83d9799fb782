// Lattice JSON: round trip, defaults, and every refusal names the file and the problem.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "systems/ffd/lattice.h"
#include "systems/ffd/lattice_io.h"
#include "systems/ffd/operations.h"

namespace sffd::ffd {
namespace {

std::string err(std::string_view text) {
    auto r = parse_lattice_json(text, "bad.json");
    return r.ok() ? std::string("ok") : r.message();
}

TEST(FfdLatticeIo, RoundTripThroughAtomicSave) {
    Lattice l =
        make_lattice({1e6, -2, 3}, {glm::dvec3(2, 0.1, 0), glm::dvec3(0, 3, 0), glm::dvec3(0.2, 0, 1)},
                     {3, 2, 4}, LatticeBasis::bspline);
    twist(l, all_control_points(l), {0, 1, 0}, 0.3);
    const auto path = std::filesystem::temp_directory_path() / "ffd_lattice_io_test.json";
    ASSERT_TRUE(save_lattice(path, l).ok());
    auto back = load_lattice(path);
    ASSERT_TRUE(back.ok()) << back.message();
    EXPECT_EQ(back->divisions, l.divisions);
    EXPECT_EQ(back->basis, l.basis);
    EXPECT_EQ(back->origin, l.origin);
    EXPECT_EQ(back->current, l.current);  // doubles written with round-trip precision
    // A baked rest (apply_as_rest) survives through "rest_control_points".
    ASSERT_TRUE(apply_as_rest(l).ok());
    ASSERT_TRUE(save_lattice(path, l).ok());
    back = load_lattice(path);
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(back->rest, l.rest);
    std::filesystem::remove(path);
}

TEST(FfdLatticeIo, ControlPointsOptionalBasisDefaultsToBernstein) {
    auto l = parse_lattice_json(R"({"origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"divisions":[1,2,3]})",
                                "x.json");
    ASSERT_TRUE(l.ok()) << l.message();
    EXPECT_EQ(l->basis, LatticeBasis::bernstein);
    EXPECT_EQ(l->size(), 2u * 3u * 4u);
    EXPECT_EQ(l->current, l->rest);
    EXPECT_EQ(l->current[l->index(1, 2, 3)], glm::dvec3(1, 1, 1));
}

TEST(FfdLatticeIo, BadFilesAreRefusedWithAClearMessage) {
    const std::string head = R"("origin":[0,0,0],"axes":[[1,0,0],[0,1,0],[0,0,1]])";
    EXPECT_NE(err("{\"origin\": [0,0").find("bad.json: malformed JSON"), std::string::npos)
        << err("{\"origin\": [0,0");
    EXPECT_NE(err("[1,2]").find("bad.json: expected a JSON object"), std::string::npos);
    EXPECT_NE(err("{" + head + "}").find("bad.json: missing \"divisions\""), std::string::npos);
    EXPECT_NE(err("{" + head + R"(,"divisions":[1,1,1],"control_points":[[0,0,0]]})")
                  .find("bad.json: expected 8 control_points ((l+1)(m+1)(n+1)), got 1"),
              std::string::npos);
    EXPECT_NE(err(R"({"origin":[0,0,0],"axes":[[1,0,0],[2,0,0],[0,0,1]],"divisions":[1,1,1]})")
                  .find("bad.json: zero-volume box"),
              std::string::npos);
    EXPECT_NE(err("{" + head + R"(,"divisions":[1,1,1],"basis":"nurbs"})").find("unknown basis \"nurbs\""),
              std::string::npos);
    EXPECT_NE(err("{" + head + R"(,"divisions":[0,1,1]})").find("divisions must be between 1 and"),
              std::string::npos);
    EXPECT_NE(err("{" + head + R"(,"divisions":[1.5,1,1]})").find("must be integers"), std::string::npos);
    EXPECT_NE(err(R"({"origin":[0,"a",0],"axes":[[1,0,0],[0,1,0],[0,0,1]],"divisions":[1,1,1]})")
                  .find("\"origin\" must be"),
              std::string::npos);
    // JSON has no NaN literal; NaN / Infinity tokens and overflowing exponents are refused.
    EXPECT_NE(
        err("{" + head +
            R"(,"divisions":[1,1,1],"control_points":[[0,0,0],[0,0,1],[0,1,0],[0,1,1],[1,0,0],[1,0,1],[1,1,0],[1,1,1e999]]})")
            .find("bad.json: malformed JSON"),
        std::string::npos);
    EXPECT_NE(
        err("{" + head +
            R"(,"divisions":[1,1,1],"control_points":[[0,0,0],[0,0,1],[0,1,0],[0,1,1],[1,0,0],[1,0,1],[1,1,0],[1,1,NaN]]})")
            .find("bad.json: malformed JSON"),
        std::string::npos);
    EXPECT_NE(
        err("{" + head +
            R"(,"divisions":[1,1,1],"control_points":[[0,0,0],[0,0,1],[0,1,0],[0,1,1],[1,0,0],[1,0,1],[1,1,0],[1,1]]})")
            .find("control_points[7] must be an array of 3 numbers"),
        std::string::npos);
    auto missing = load_lattice("/nonexistent/l.json");
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.message().find("/nonexistent/l.json: cannot open"), std::string::npos);
}

}  // namespace
}  // namespace sffd::ffd
