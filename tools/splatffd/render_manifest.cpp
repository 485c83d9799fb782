#include "tools/splatffd/render_manifest.h"

#include <array>
#include <cstdio>
#include <fstream>
#include <memory>
#include <system_error>

#include "runtime/core/atomic_file.h"
#include "tools/splatffd/command.h"

namespace sffd::cli {

using ojson = nlohmann::ordered_json;

Result<Shard> parse_shard(const std::string& text) {
    const auto slash = text.find('/');
    if (slash == std::string::npos)
        return make_error("--shard: expected K/N (shard K of N, 0 <= K < N), got '" + text + "'");
    auto n = parse_integer("--shard", text.substr(slash + 1), 1, 100'000);
    if (!n) return n.error();
    auto k = parse_integer("--shard", text.substr(0, slash), 0, *n - 1);
    if (!k) return k.error();
    return Shard{static_cast<long>(*k), static_cast<long>(*n)};
}

FrameSequence shard_frames(long first, long last, const Shard& shard) {
    FrameSequence s{first + shard.index, shard.count, 0};
    if (s.first <= last) s.count = (last - s.first) / shard.count + 1;
    return s;
}

std::filesystem::path manifest_path(const std::filesystem::path& dir, const Shard& shard, bool sharded) {
    if (!sharded) return dir / "render_manifest.json";
    return dir / ("render_manifest.shard-" + std::to_string(shard.index) + "-of-" +
                  std::to_string(shard.count) + ".json");
}

Result<FilePrint> fingerprint(const std::filesystem::path& file) {
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "rb"), &std::fclose);
    if (!f) return make_error(file.string() + ": cannot read");
    FilePrint p;
    p.fnv1a64 = 14695981039346656037ull;
    std::array<unsigned char, 1 << 16> buf{};
    while (const std::size_t n = std::fread(buf.data(), 1, buf.size(), f.get())) {
        for (std::size_t i = 0; i < n; ++i) p.fnv1a64 = (p.fnv1a64 ^ buf[i]) * 1099511628211ull;
        p.bytes += n;
    }
    if (std::ferror(f.get())) return make_error(file.string() + ": read error");
    return p;
}

std::string hex64(std::uint64_t v) {
    char s[17];
    std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
    return s;
}

namespace {

ojson print_json(const FilePrint& p) { return ojson{{"bytes", p.bytes}, {"fnv1a64", hex64(p.fnv1a64)}}; }

std::optional<FilePrint> print_from(const ojson& j) {
    if (!j.is_object()) return std::nullopt;
    FilePrint p;
    p.bytes = j.at("bytes").get<std::uint64_t>();
    p.fnv1a64 = std::stoull(j.at("fnv1a64").get<std::string>(), nullptr, 16);
    return p;
}

}  // namespace

ojson to_json(const RunRecord& r) {
    ojson j;
    j["generator"] = "splatffd render " SFFD_VERSION;
    j["state"] = r.state;
    j["complete"] = r.state == "complete";
    j["started_unix"] = r.started_unix;
    j["command"] = r.command;
    j["settings"] = r.settings;
    j["machine"] = ojson{{"simd", r.machine.simd}, {"gl_renderer", r.machine.gl_renderer}};
    j["shard"] = ojson{{"index", r.shard.index}, {"count", r.shard.count}, {"sharded", r.sharded}};
    j["frames"] = ojson{{"first", r.frames.first}, {"step", r.frames.step}, {"count", r.frames.count}};
    // The frames on disk are the first `count` of the sequence above; `last` says which one ends them.
    j["frames_written"] = ojson{{"count", r.written},
                                {"last", r.written > 0 ? ojson(r.frames.at(r.written - 1)) : ojson(nullptr)}};
    if (r.state != "running") {
        ojson files = ojson::array();
        for (const FramePrint& f : r.files) {
            ojson e{{"frame", f.frame}};
            if (f.png) e["png"] = print_json(*f.png);
            if (f.exr) e["exr"] = print_json(*f.exr);
            files.push_back(std::move(e));
        }
        j["files"] = std::move(files);
    }
    return j;
}

Status write_manifest(const std::filesystem::path& path, const RunRecord& r) {
    return write_file_atomic(path, to_json(r).dump(2, ' ', false, ojson::error_handler_t::replace) + "\n");
}

Result<RunRecord> read_manifest(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return make_error(path.string() + ": cannot read");
    try {
        const ojson j = ojson::parse(in);
        RunRecord r;
        r.state = j.at("state").get<std::string>();
        r.started_unix = j.at("started_unix").get<long long>();
        r.command = j.at("command").get<std::string>();
        r.settings = j.at("settings");
        if (const auto m = j.find("machine"); m != j.end()) {
            r.machine.simd = m->at("simd").get<std::string>();
            r.machine.gl_renderer = m->at("gl_renderer").get<std::string>();
        }
        // What `assemble` reads from the settings, checked here so a hand-edited manifest is named.
        (void)r.settings.at("first").get<long>(), (void)r.settings.at("last").get<long>();
        (void)r.settings.at("formats").get<std::string>(), (void)r.settings.at("fps").get<double>();
        r.shard = Shard{j.at("shard").at("index").get<long>(), j.at("shard").at("count").get<long>()};
        r.sharded = j.at("shard").at("sharded").get<bool>();
        r.frames =
            FrameSequence{j.at("frames").at("first").get<long>(), j.at("frames").at("step").get<long>(),
                          j.at("frames").at("count").get<long>()};
        r.written = j.at("frames_written").at("count").get<long>();
        if (r.shard.count < 1 || r.shard.index < 0 || r.shard.index >= r.shard.count || r.frames.step < 1 ||
            r.written < 0 || r.written > r.frames.count)
            return make_error(path.string() + ": inconsistent shard or frame counts");
        if (j.contains("files")) {
            for (const ojson& e : j.at("files")) {
                FramePrint f;
                f.frame = e.at("frame").get<long>();
                if (e.contains("png")) f.png = print_from(e.at("png"));
                if (e.contains("exr")) f.exr = print_from(e.at("exr"));
                r.files.push_back(f);
            }
        }
        return r;
    } catch (const std::exception& e) {
        // nlohmann's messages name the position; the field that is missing or mistyped comes with it.
        return make_error(path.string() + ": not a render manifest (" + e.what() + ")");
    }
}

std::string shell_quote(const std::string& s) {
    bool plain = !s.empty();
    for (char c : s) {
        const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                        std::string_view("-_./:,=+@%").find(c) != std::string_view::npos;
        plain = plain && ok;
    }
    if (plain) return s;
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

Status check_free_space(const std::string& out_dir, long frames, double bytes_per_frame, const char* basis,
                        const char* verb) {
    std::error_code ec;
    const std::filesystem::space_info space = std::filesystem::space(out_dir, ec);
    if (ec) return {};
    const auto gigabytes = [](double bytes) {
        char s[32];
        std::snprintf(s, sizeof s, "%.3g GB", bytes / 1e9);
        return std::string(s);
    };
    const double need = double(frames) * bytes_per_frame;
    if (need <= double(space.available)) return {};
    return make_error(out_dir + ": " + std::to_string(frames) + " frames need about " + gigabytes(need) +
                      " (" + basis + ") but the file system has " + gigabytes(double(space.available)) +
                      " free; " + verb + " fewer frames (--frames, --shard) or free some space");
}

}  // namespace sffd::cli
