// What `splatffd render` records about a run, and what `splatffd assemble` reads back: the shard a run
// renders, the manifest file it keeps, and the fingerprint of every frame file it wrote.
//
// A clip of frames FIRST..LAST split into N shards: shard K renders FIRST+K, FIRST+K+N, ... (interleaved,
// so shards take equal time when the load changes along the clip). Frame k is the same bytes in any shard,
// so the shards write the same file names as a single run, into one shared folder. Each run owns one
// manifest, so shards never race on a file:
//   DIR/render_manifest.json                a run without --shard (and the assembled result)
//   DIR/render_manifest.shard-K-of-N.json   shard K of N
// The manifest is rewritten after every frame at a constant size (the frames written are the first
// `count` of the shard's arithmetic sequence), so a long clip costs O(1) per frame; the per-frame
// fingerprints (bytes and FNV-1a 64 of each file) are written once, when the run ends.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/core/result.h"

namespace sffd::cli {

struct Shard {
    long index = 0;  // K in 0..count-1
    long count = 1;  // N
};

// "K/N" with 0 <= K < N <= 100000; the message names --shard.
Result<Shard> parse_shard(const std::string& text);

// The frames of `shard` in FIRST..LAST: FIRST+K, FIRST+K+N, ... (none when FIRST+K > LAST).
struct FrameSequence {
    long first = 0;  // the shard's first frame
    long step = 1;
    long count = 0;
    long at(long i) const { return first + i * step; }
};
FrameSequence shard_frames(long first, long last, const Shard& shard);

// DIR/render_manifest.json (single run, N = 1) or DIR/render_manifest.shard-K-of-N.json.
std::filesystem::path manifest_path(const std::filesystem::path& dir, const Shard& shard, bool sharded);

// One frame file's fingerprint.
struct FilePrint {
    std::uint64_t bytes = 0;
    std::uint64_t fnv1a64 = 0;
};
Result<FilePrint> fingerprint(const std::filesystem::path& file);
std::string hex64(std::uint64_t v);

// Refuses `frames` frames of `bytes_per_frame` each when DIR's file system has less free space, so a
// mistyped range (--frames 0:99999999) stops at once instead of filling the disk. `basis` says where the
// size comes from; `verb` ("render", "export") goes into the advice. A file system that does not say
// passes.
Status check_free_space(const std::string& out_dir, long frames, double bytes_per_frame, const char* basis,
                        const char* verb);

struct FramePrint {
    long frame = 0;
    std::optional<FilePrint> png, exr;
};

// The manifest's contents. `settings` holds everything that decides the pixels (scene, range, size,
// quality, formats, fps, culling, background, camera, turntable) and the binary's version: shards of one
// clip have equal settings.
// What made the pixels besides the settings: the CPU kernels' SIMD target (runtime/simd) and the GL
// renderer. Equal settings give equal bytes only on equal machines: `assemble` warns when shards differ
// here, and pinning SFFD_SIMD makes the CPU side equal across a farm's mixed nodes.
struct MachineRecord {
    std::string simd;         // e.g. "avx2"; empty in manifests from before it was recorded
    std::string gl_renderer;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
    bool operator==(const MachineRecord&) const = default;
};

struct RunRecord {
    std::string state = "running";  // running | complete | failed
    long long started_unix = 0;
    std::string command;  // the shell line that re-runs this run (shard)
    nlohmann::ordered_json settings;
    MachineRecord machine;
    Shard shard;
    bool sharded = false;
    FrameSequence frames;
    long written = 0;               // the first `written` frames of `frames` are on disk
    std::vector<FramePrint> files;  // only when state != running
};

nlohmann::ordered_json to_json(const RunRecord& r);
// Atomic (temporary + rename); invalid UTF-8 in strings (a file name) is replaced, never thrown.
Status write_manifest(const std::filesystem::path& path, const RunRecord& r);
// Reads a manifest written by write_manifest; the message names the file and what is wrong.
Result<RunRecord> read_manifest(const std::filesystem::path& path);

// Quotes `s` for a POSIX shell when it needs it ('it'\''s').
std::string shell_quote(const std::string& s);

}  // namespace sffd::cli
