// The Potree 2 commands: `splatffd convert IN DIR/metadata.json` builds a Potree 2 octree of surface
// splats (runtime/assets/formats/surface/potree2_write.h: out of core, in a memory budget) and `splatffd
// info DIR/metadata.json` describes one (potree2.h). cmd_convert.cpp and cmd_info.cpp hand these over as
// soon as they see a metadata.json where it applies; `render DIR/metadata.json` needs nothing here (the
// scene loader reads it at full detail).
#pragma once

#include <string>

#include "tools/splatffd/command.h"

namespace sffd::cli {

// True when `args` (convert's, after the command name) name a metadata.json output: an argument after the
// first plain one (IN) whose file name is metadata.json.
bool names_potree_output(Args args);
// `splatffd convert IN DIR/metadata.json [--potree-* ...]`; returns the exit code.
int run_convert_potree(Args args);
// `splatffd info DIR/metadata.json`; returns the exit code.
int info_potree(const std::string& file);

}  // namespace sffd::cli
