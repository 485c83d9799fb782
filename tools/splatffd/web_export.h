// `splatffd export SCENE --web DIR`: a self-contained web player folder that plays the scene's keyframed
// lattice deformation of one 3D Gaussian cloud in a browser (README.md, "Web player").
//
// The folder holds index.html, the PlayCanvas engine (copied from the npm package that
// tools/fetch_web_engine.sh installs, never fetched at view time), player.js and ffd_glsl.js (the FFD
// evaluation as a gsplat shader hook), capture.js (the Gaussians as SOG bytes, base64) and scene.js (the
// lattice at rest, its clip, the cloud's transform and the camera). Every data file is a classic script,
// so the page works from file:// (where browsers refuse fetch and module scripts) as from a static server.
//
// `splatffd export` (cmd_export.cpp) hands any argument list that holds --web to run_export_web().
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "tools/splatffd/command.h"

namespace sffd::cli {

// Options after the scene: --web DIR, --force, --size WxH (the canvas and the camera's aspect), --fps F
// (the scrub slider's step and the frame numbering of ?frame=K). Exit 0 ok, 1 bad input, 2 usage.
int run_export_web(sffd::cli::Args args);

// Where the engine file comes from, first found: $SPLATFFD_WEB_ENGINE (a file; set but missing means
// missing), <exe dir>/web/playcanvas.min.js (the build copies it there), <data root>/web/playcanvas.min.js
// (installed), <cache>/web/node_modules/playcanvas/build/playcanvas.min.js (the npm install itself).
std::optional<std::filesystem::path> find_web_engine();

}  // namespace sffd::cli
