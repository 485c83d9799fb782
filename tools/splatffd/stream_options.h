// The options view, render and profile share for level-of-detail hierarchies (a streamed SOG's
// lod-meta.json, a Potree 2 metadata.json written by splatffd), which they open by streaming
// (systems/lod/streaming.h) unless --full-detail reads the whole finest level as any other cloud.
#pragma once

#include <cstddef>
#include <string>

#include "runtime/ecs/registry.h"
#include "systems/lod/streaming.h"
#include "tools/splatffd/command.h"

namespace sffd::cli {

struct StreamCli {
    bool full_detail = false;
    lod::StreamSettings settings;
};

// The usage lines, the same in every command.
extern const char* const kStreamUsage;

// The defaults of an interactive command (view, profile): a cut of at most 1M splats at 1 pixel of
// error, 1 GiB of pieces. A final render: every node in view at full detail (no splat budget, error 0),
// each frame waiting for its cut.
StreamCli interactive_stream_defaults();
StreamCli final_render_stream_defaults();

// Reads args[i] (and its value) when it is one of the stream options: 1 taken (i on its value), 0 not a
// stream option, -1 a bad value (the message printed, naming `command`).
int parse_stream_option(std::string_view command, const Args& args, std::size_t& i, StreamCli& out);

// Before load_scene: the registry opens hierarchies by streaming with these settings (nothing with
// --full-detail).
void apply_stream_options(ecs::Registry& registry, const StreamCli& options);

}  // namespace sffd::cli
