// The level-of-detail commands: `splatffd convert IN DIR/lod-meta.json` builds a streamed SOG hierarchy
// (runtime/assets/formats/lod/lod_build.h: out of core, in a memory budget) and `splatffd info
// DIR/lod-meta.json` describes one (streamed_sog.h). cmd_convert.cpp and cmd_info.cpp hand these over as
// soon as they see a lod-meta.json where it applies; everything else about the two commands stays there.
#pragma once

#include <string>

#include "tools/splatffd/command.h"

namespace sffd::cli {

// True when `args` (convert's, after the command name) name a lod-meta.json output: an argument after the
// first plain one (IN) whose file name is lod-meta.json. A lod-meta.json IN with another OUT is read as
// Gaussians (its finest level) by convert's ordinary path.
bool names_lod_output(Args args);
// `splatffd convert IN DIR/lod-meta.json [--lod-* ...]`; returns the exit code.
int run_convert_lod(Args args);
// `splatffd info DIR/lod-meta.json`; returns the exit code.
int info_lod(const std::string& file);

}  // namespace sffd::cli
