// splatffd compare A.exr B.exr [--whole-image | --mask-alpha]
//
// PSNR and SSIM between two frames (systems/splat_render/image_compare.h): over the object (pixels covered
// in either image) by default, over every pixel with --whole-image. Prints one line:
//   psnr_db=37.12 ssim=0.9876 pixels=140233 mse=1.94e-04 psnr_both_db=38.50 pixels_both=139000
//   pixels_one=1233 psnr_interior_db=45.10 pixels_interior=120000
// (then: the pixels covered in both images alone, the silhouette disagreement, and the interior: pixels 2+
// px from B's silhouettes and creases (B's normals turn < 10 degrees in 5 x 5, A's within 10 degrees of
// B's), texture and shading only)
// Exit 0 ok, 1 unreadable file or size mismatch (the message names the file), 2 usage.
#include <cstdio>
#include <string>
#include <vector>

#include "systems/splat_render/image_compare.h"
#include "systems/splat_render/image_io.h"
#include "tools/splatffd/command.h"

namespace {

using namespace sffd;

constexpr const char* kUsage =
    "usage: splatffd compare A.exr B.exr [--whole-image | --mask-alpha]\n"
    "  A.exr B.exr    two frames of the same size (splatffd render / reference --format exr)\n"
    "  --mask-alpha   PSNR (dB) and SSIM of sRGB colour over the pixels covered in either image (default)\n"
    "  --whole-image  over every pixel\n"
    "Prints one line: psnr_db ssim pixels mse psnr_both_db pixels_both pixels_one psnr_interior_db "
    "pixels_interior\n";

int run_compare(sffd::cli::Args args) {
    std::vector<std::string> files;
    bool object_only = true;
    for (const std::string& a : args) {
        if (cli::is_help(a)) return cli::help(kUsage);
        if (a == "--whole-image") object_only = false;
        else if (a == "--mask-alpha") object_only = true;
        else if (!a.empty() && a[0] != '-') files.push_back(a);
        else return cli::usage_error("compare", "unknown option '" + a + "'", kUsage);
    }
    if (files.size() != 2)
        return cli::usage_error("compare", "expected two EXR files, got " + std::to_string(files.size()),
                                kUsage);
    auto a = render::read_exr(files[0]);
    if (!a) {
        cli::command_error("compare", a.message());
        return 1;
    }
    auto b = render::read_exr(files[1]);
    if (!b) {
        cli::command_error("compare", b.message());
        return 1;
    }
    auto r = render::compare_images(*a, *b, object_only);
    if (!r) {
        cli::command_error("compare", files[0] + " vs " + files[1] + ": " + r.message());
        return 1;
    }
    std::printf(
        "psnr_db=%.2f ssim=%.4f pixels=%zu mse=%.3e psnr_both_db=%.2f pixels_both=%zu pixels_one=%zu "
        "psnr_interior_db=%.2f "
        "pixels_interior=%zu\n",
        r->psnr, r->ssim, r->pixels, r->mse, r->psnr_both, r->pixels_both, r->pixels_one, r->psnr_interior,
        r->pixels_interior);
    return 0;
}

}  // namespace

SFFD_COMMAND(compare, "PSNR and SSIM between two EXR frames over the object", run_compare);
