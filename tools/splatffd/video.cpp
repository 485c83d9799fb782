#include "tools/splatffd/video.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <system_error>
#include <vector>

extern char** environ;

namespace sffd::cli {

std::string find_on_path(const std::string& name) {
    const char* path = std::getenv("PATH");
    std::string dirs = path ? path : "/usr/bin:/bin";
    std::size_t start = 0;
    while (start <= dirs.size()) {
        const std::size_t end = std::min(dirs.find(':', start), dirs.size());
        const std::string dir = dirs.substr(start, end - start);
        const std::filesystem::path candidate = std::filesystem::path(dir.empty() ? "." : dir) / name;
        std::error_code ec;
        if (std::filesystem::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0)
            return candidate.string();
        start = end + 1;
    }
    return {};
}

Status encode_video(const std::string& ffmpeg, const std::filesystem::path& dir, long first, long last,
                    double fps, const std::filesystem::path& video, glm::vec3 background) {
    const bool gif = video.extension() == ".gif";
    const std::filesystem::path tmp =
        video.parent_path() / (video.filename().string() + ".tmp" + std::to_string(::getpid()));
    char rate[64];
    std::snprintf(rate, sizeof rate, "%.9g", fps);
    std::vector<std::string> argv = {ffmpeg,
                                     "-nostdin",
                                     "-loglevel",
                                     "error",
                                     "-y",
                                     "-framerate",
                                     rate,
                                     "-start_number",
                                     std::to_string(first),
                                     "-i",
                                     (dir / "frame_%04d.png").string(),
                                     "-frames:v",
                                     std::to_string(last - first + 1)};
    // Both formats are flattened over the same opaque `background` (sRGB) first: H.264 has no alpha and a
    // GIF's one transparent index cannot hold soft edges, and left to ffmpeg the MP4 came out black where the
    // GIF was transparent. The PNG's straight alpha is blended in display (sRGB) space, as 3DGS viewers do.
    char colour[16];
    const auto byte = [](float c) {
        return static_cast<unsigned>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
    };
    std::snprintf(colour, sizeof colour, "0x%02X%02X%02X", byte(background.x), byte(background.y),
                  byte(background.z));
    // [bg] is the colour as a stream as long as the frames; overlay=shortest=1 ends with the last frame.
    const std::string flatten = std::string("[0:v]split[in][size];[size]format=rgb24,drawbox=c=") + colour +
                                ":t=fill[bg];[bg][in]overlay=shortest=1:format=rgb";
    if (gif) {
        argv.insert(argv.end(),
                    {"-filter_complex",
                     flatten + ",split[a][b];[a]palettegen=reserve_transparent=0[p];[b][p]paletteuse",
                     "-loop", "0", "-f", "gif"});
    } else {
        // The padding is the background too, so the extra column or row is not a black line.
        argv.insert(argv.end(),
                    {"-filter_complex", flatten + ",pad=ceil(iw/2)*2:ceil(ih/2)*2:color=" + colour, "-c:v",
                     "libx264", "-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4"});
    }
    argv.push_back(tmp.string());
    std::vector<char*> args;
    for (std::string& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    pid_t pid = 0;
    if (int err = posix_spawn(&pid, ffmpeg.c_str(), nullptr, nullptr, args.data(), environ); err != 0)
        return make_error(video.string() + ": cannot run " + ffmpeg + ": " + std::strerror(err));
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    std::error_code ec;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::filesystem::remove(tmp, ec);
        return make_error(
            video.string() + ": ffmpeg failed (" +
            (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status)) : std::string("killed")) +
            "); its messages are above");
    }
    std::filesystem::rename(tmp, video, ec);
    if (ec) {
        std::filesystem::remove(tmp, ec);
        return make_error(video.string() + ": cannot write: " + ec.message());
    }
    return {};
}

std::string video_size_note(const std::filesystem::path& video, long width, long height) {
    if (video.extension() != ".mp4" || (width % 2 == 0 && height % 2 == 0)) return {};
    const long w = width + width % 2, h = height + height % 2;
    return video.string() + ": " + std::to_string(width) + "x" + std::to_string(height) + " padded to " +
           std::to_string(w) + "x" + std::to_string(h) +
           " with the background colour (H.264 needs an even width and height; the frames keep " +
           std::to_string(width) + "x" + std::to_string(height) + ", and so would a .gif)";
}

Result<std::string> check_video_output(const std::string& video, bool& usage) {
    usage = true;
    const std::string ext = std::filesystem::path(video).extension().string();
    if (ext != ".mp4" && ext != ".gif")
        return make_error("--video " + video + ": the file must end in .mp4 or .gif");
    usage = false;
    const std::string ffmpeg = find_on_path("ffmpeg");
    if (ffmpeg.empty())
        return make_error(
            "--video needs ffmpeg, which is not on PATH; install it (Debian/Ubuntu: "
            "apt-get install ffmpeg) or encode the PNG frames yourself");
    const std::filesystem::path parent = std::filesystem::absolute(video).parent_path();
    std::error_code ec;
    if (!std::filesystem::is_directory(parent, ec) || ::access(parent.c_str(), W_OK) != 0)
        return make_error(video + ": cannot write the video: folder " + parent.string() +
                          " does not exist or is not writable");
    return ffmpeg;
}

}  // namespace sffd::cli
