// The engine's standard frame: which system runs in which phase. `view`, `render` and `profile` all run
// this Schedule through app::run() (runtime/app/app.h), so the three commands execute the same frame.
#pragma once

#include <string>

#include "runtime/app/frame_loop.h"

namespace sffd {

struct EngineScheduleOptions {
    bool present = true;  // the present phase: display copy, blit, swap (each does nothing headless)
    bool editor = false;  // the editor's overlay, requests and panels (`splatffd view`)
};

// Every system declares the components and resources it reads and writes (ecs::reads/writes, checked
// by builds with SFFD_CHECK_ACCESS).
Schedule make_engine_schedule(const EngineScheduleOptions& options = {});

// The frame table of the top README (between its frame-table markers): one row per system of the
// editor's schedule, in run order, with its declared reads and writes. `splatffd schedule --markdown`
// prints it; tests/systems/engine checks the README against it.
std::string frame_table_markdown();

}  // namespace sffd
