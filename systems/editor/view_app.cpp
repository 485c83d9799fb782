#include "systems/editor/view_app.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include "runtime/app/app.h"
#include "runtime/app/clock.h"
#include "runtime/assets/scene.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/log.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/render_target.h"
#include "systems/animation/unkeyed_edit.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/file_browser.h"
#include "systems/editor/lattice_manage.h"
#include "systems/editor/lattice_overlay.h"
#include "systems/editor/panels.h"
#include "systems/editor/ui_cache.h"
#include "systems/editor/session_state.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_render.h"
#include "systems/profiling/profiler.h"

namespace sffd::editor {

namespace {

// Where GLFW callbacks deliver events: run_view points the window's user pointer at one of these for
// as long as the window feeds this registry (and clears it before the registry goes), so the C callbacks
// reach the registry without file-level state.
struct CallbackLink {
    ecs::Registry* registry = nullptr;
    bool ui = false;
};

std::uint8_t glfw_mods(int m) {
    return std::uint8_t(((m & GLFW_MOD_SHIFT) ? mods::shift : 0) | ((m & GLFW_MOD_CONTROL) ? mods::ctrl : 0) |
                        ((m & GLFW_MOD_ALT) ? mods::alt : 0));
}

std::string glfw_key_name(int key) {
    if (key >= GLFW_KEY_A && key <= GLFW_KEY_Z) return std::string(1, char('a' + (key - GLFW_KEY_A)));
    if (key >= GLFW_KEY_0 && key <= GLFW_KEY_9) return std::string(1, char('0' + (key - GLFW_KEY_0)));
    if (key >= GLFW_KEY_KP_0 && key <= GLFW_KEY_KP_9)
        return std::string(1, char('0' + (key - GLFW_KEY_KP_0)));  // typed values
    if (key >= GLFW_KEY_F1 && key <= GLFW_KEY_F12) {
        std::string name = std::to_string(key - GLFW_KEY_F1 + 1);
        name.insert(name.begin(), 'f');  // not "f" + string: GCC 12 warns (-Wrestrict) on that inlined path
        return name;
    }
    switch (key) {
        case GLFW_KEY_ESCAPE: return "escape";
        case GLFW_KEY_ENTER:
        case GLFW_KEY_KP_ENTER: return "enter";
        case GLFW_KEY_KP_DECIMAL: return "period";
        case GLFW_KEY_KP_SUBTRACT: return "minus";
        case GLFW_KEY_KP_ADD: return "plus";  // ctrl+keypad + grows the point selection
        case GLFW_KEY_TAB: return "tab";
        case GLFW_KEY_BACKSPACE: return "backspace";
        case GLFW_KEY_DELETE: return "delete";
        case GLFW_KEY_SPACE: return "space";
        case GLFW_KEY_LEFT: return "left";
        case GLFW_KEY_RIGHT: return "right";
        case GLFW_KEY_UP: return "up";
        case GLFW_KEY_DOWN: return "down";
        case GLFW_KEY_HOME: return "home";
        case GLFW_KEY_END: return "end";
        case GLFW_KEY_MINUS: return "minus";
        case GLFW_KEY_EQUAL: return "equal";
        case GLFW_KEY_PERIOD: return "period";
        case GLFW_KEY_PAGE_UP: return "pageup";
        case GLFW_KEY_PAGE_DOWN: return "pagedown";
        case GLFW_KEY_INSERT: return "insert";
        case GLFW_KEY_COMMA: return "comma";
        case GLFW_KEY_SLASH: return "slash";
        default: return {};
    }
}

const CallbackLink* link_of(GLFWwindow* window) {
    return window ? static_cast<const CallbackLink*>(glfwGetWindowUserPointer(window)) : nullptr;
}
EditorState* live_state(GLFWwindow* window) {
    const CallbackLink* link = link_of(window);
    return link && link->registry ? link->registry->try_resource<EditorState>() : nullptr;
}
bool ui_wants_mouse(GLFWwindow* window) {
    const CallbackLink* link = link_of(window);
    return link && link->ui && ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse;
}
bool ui_wants_keyboard(GLFWwindow* window) {
    const CallbackLink* link = link_of(window);
    return link && link->ui && ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureKeyboard;
}

glm::dvec2 to_pixels(GLFWwindow* window, double x, double y) {
    int ww = 0, wh = 0, fw = 0, fh = 0;
    glfwGetWindowSize(window, &ww, &wh);
    glfwGetFramebufferSize(window, &fw, &fh);
    return {ww > 0 ? x * fw / ww : x, wh > 0 ? y * fh / wh : y};
}

void on_cursor(GLFWwindow* window, double x, double y) {
    EditorState* s = live_state(window);
    if (!s || s->replay) return;  // a replay owns the input
    InputEvent e;
    e.kind = InputKind::move;
    e.position = to_pixels(window, x, y);
    s->events.push_back(e);
}

void on_button(GLFWwindow* window, int button, int action, int m) {
    EditorState* s = live_state(window);
    if (!s || s->replay) return;
    InputEvent e;
    e.kind = action == GLFW_PRESS ? InputKind::press : InputKind::release;
    if (button == GLFW_MOUSE_BUTTON_LEFT) e.button = MouseButton::left;
    else if (button == GLFW_MOUSE_BUTTON_RIGHT) e.button = MouseButton::right;
    else if (button == GLFW_MOUSE_BUTTON_MIDDLE) e.button = MouseButton::middle;
    else return;
    // Presses over a panel belong to the panel; releases always reach the editor (ends its drags).
    if (e.kind == InputKind::press && ui_wants_mouse(window)) return;
    e.modifiers = glfw_mods(m);
    s->events.push_back(e);
}

void on_scroll(GLFWwindow* window, double, double dy) {
    EditorState* s = live_state(window);
    if (!s || s->replay || ui_wants_mouse(window)) return;
    InputEvent e;
    e.kind = InputKind::scroll;
    e.scroll = dy;
    s->events.push_back(e);
}

void on_key(GLFWwindow* window, int key, int, int action, int m) {
    EditorState* s = live_state(window);
    // ctrl+q quits even while a panel or the file dialog has the keyboard.
    const bool quit = key == GLFW_KEY_Q && (m & GLFW_MOD_CONTROL);
    if (!s || s->replay || action == GLFW_RELEASE || (ui_wants_keyboard(window) && !quit)) return;
    std::string name = glfw_key_name(key);
    if (name.empty()) return;
    InputEvent e;
    e.kind = InputKind::key;
    e.key = std::move(name);
    e.modifiers = glfw_mods(m);
    s->events.push_back(e);
}

}  // namespace

std::string user_config_file(const std::string& name) {
    std::filesystem::path dir;
    if (const char* xdg = std::getenv("XDG_CONFIG_HOME"); xdg && *xdg) dir = xdg;
    else if (const char* home = std::getenv("HOME"); home && *home)
        dir = std::filesystem::path(home) / ".config";
    else return {};
    dir /= "splatffd";
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) {
        log::warn("view: cannot create ", dir.string(), ": ", ec.message(), " (settings are not remembered)");
        return {};
    }
    return (dir / name).string();
}

// View-only resource (named in session_state.h): options the request handler needs and the per-frame drag
// log for timing.
struct detail::ViewSession {
    ViewOptions options;
    std::string save_path;
    int screenshot_count = 0;
    std::vector<std::uint8_t> dragging;  // per frame: 1 when a tool drag was active
    bool ui = false;
};
using detail::ViewSession;

namespace {

Status write_screenshot(ecs::Registry& registry, const std::filesystem::path& path) {
    auto frame = render::capture_frame(registry);
    if (!frame) return make_error(frame.message());
    // capture_frame keeps colour only where a splat was hit; the lattice overlay is also drawn where no
    // surface is behind it (opaque, alpha 1), so take those pixels from the colour target itself.
    if (auto color = render::capture_output_color(registry); color) {
        const int w = frame->width, h = frame->height;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const glm::vec4& c = (*color)[std::size_t(y) * std::size_t(w) + std::size_t(x)];
                glm::vec4& dst = frame->color[frame->index(x, y)];
                if (dst.w <= 0.0f && c.w >= 1.0f) dst = c;  // overlay over background
            }
    }
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".exr") return render::write_exr(path, *frame);
    if (ext == ".png") return render::write_png(path, render::to_rgba8(*frame, glm::vec3(0.0f)));
    return make_error(path.string() + ": screenshot must end in .png or .exr");
}

}  // namespace

void requests_system(ecs::Registry& registry, const FrameContext& frame) {
    EditorState* state = registry.try_resource<EditorState>();
    ViewSession* session = registry.try_resource<ViewSession>();
    if (!state || !session) return;
    if (session->dragging.size() <= frame.frame) session->dragging.resize(frame.frame + 1, 0);
    session->dragging[frame.frame] =
        state->drag.kind == Drag::Kind::move || state->drag.kind == Drag::Kind::twist;
    if (!state->save_as.empty()) {  // File > Save as: the new ctrl+s target
        session->save_path = std::move(state->save_as);
        state->save_as.clear();
    }
    if (state->request_save) {
        state->request_save = false;
        if (Status st = save_scene(registry, session->save_path); st) {
            state->status = "saved " + session->save_path;
            log::info("editor: ", state->status);
            // The file keeps an un-keyed edit at its clip time only; every other time shows the clip.
            for (const UnkeyedEditReport& edit : unkeyed_edits(registry)) {
                const std::string warning =
                    edit.name + " has an " + describe_unkeyed_edit(edit) + " (k keys it)";
                state->status += "; " + warning;
                log::warn("editor: ", session->save_path, ": ", warning);
            }
        } else {
            state->status = "save failed: " + st.message();
            log::error("editor: ", state->status);
        }
    }
    if (state->request_screenshot) {
        state->request_screenshot = false;
        // In the last folder of the file dialogs (remembered between runs), else the current one.
        const std::string name =
            "splatffd-screenshot-" + std::to_string(session->screenshot_count++) + ".png";
        const std::string path =
            state->last_folder.empty() ? name : (std::filesystem::path(state->last_folder) / name).string();
        const Status st = write_screenshot(registry, path);
        state->status = st ? "screenshot " + path : "screenshot failed: " + st.message();
        log::info("editor: ", state->status);
    }
    if (state->request_quit)
        if (auto* app = registry.try_resource<app::AppContext>()) app->quit_requested = true;
    // What the window shows is render::display_system's (present phase): the encoded frame, overlay included.
}

void ui_system(ecs::Registry& registry, const FrameContext& frame) {
    ViewSession* session = registry.try_resource<ViewSession>();
    if (!session || !session->ui) return;
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    draw_panels(registry, frame);
    ImGui::Render();
    draw_ui(registry, *ImGui::GetDrawData(), panel_backgrounds(registry));
    const ViewOptions& o = session->options;
    if (!o.panel_rects_json.empty() && o.frames > 0 && frame.frame + 1 == o.frames) {
        // {"window": [w, h], "panels": [{"name": .., "x": .., "y": .., "w": .., "h": ..}, ..]}
        const ImVec2 size = ImGui::GetMainViewport()->Size;
        char line[256];
        std::snprintf(line, sizeof line, "{\n  \"window\": [%g, %g],\n  \"panels\": [", double(size.x),
                      double(size.y));
        std::string json = line;
        const auto rects = panel_rects(registry);
        for (std::size_t i = 0; i < rects.size(); ++i) {
            const PanelRect& r = rects[i].rect;
            std::snprintf(
                line, sizeof line, "%s\n    {\"name\": \"%s\", \"x\": %g, \"y\": %g, \"w\": %g, \"h\": %g}",
                i ? "," : "", rects[i].name.c_str(), double(r.x), double(r.y), double(r.w), double(r.h));
            json += line;
        }
        json += "\n  ]\n}\n";
        if (Status st = write_file_atomic(o.panel_rects_json, json); !st) log::error("view: ", st.message());
    }
    if (!o.window_screenshot.empty() && o.frames > 0 && frame.frame + 1 == o.frames) {
        // The default framebuffer before the swap: what the user sees, panels included.
        GLint vp[4] = {0, 0, 0, 0};
        glGetIntegerv(GL_VIEWPORT, vp);
        render::Rgba8Image img;
        img.width = vp[2], img.height = vp[3];
        img.pixels.resize(std::size_t(img.width) * std::size_t(img.height) * 4);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
        glReadBuffer(GL_BACK);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, img.width, img.height, GL_RGBA, GL_UNSIGNED_BYTE, img.pixels.data());
        gfx::flip_rows(img.pixels, std::size_t(img.width) * 4);
        for (std::size_t i = 3; i < img.pixels.size(); i += 4) img.pixels[i] = 255;
        if (Status st = render::write_png(o.window_screenshot, img); !st) log::error("view: ", st.message());
    }
}

namespace {

std::string default_save_path(const std::string& scene) {
    const std::filesystem::path p(scene);
    const std::string ext = p.extension().string();
    if (ext == ".glb" || ext == ".gltf") return scene;
    // Next to the scene file (not in the current folder); a built-in name has no folder.
    return (p.parent_path() / ((p.stem().empty() ? std::string("scene") : p.stem().string()) + ".glb"))
        .string();
}

double percentile(std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const double at = q * double(v.size() - 1);
    const std::size_t lo = std::size_t(at);
    const std::size_t hi = std::min(lo + 1, v.size() - 1);
    return v[lo] + (v[hi] - v[lo]) * (at - double(lo));
}

}  // namespace

int run_view(const ViewOptions& options, Schedule schedule) {
    const bool headless = options.headless || !gfx::display_available();
    if (!options.headless && headless) {
        std::fprintf(
            stderr,
            "splatffd view: no display (DISPLAY is not set): run under `xvfb-run -a`, or pass --headless\n");
        return 1;
    }
    auto ctx = gfx::create_context({.headless = headless,
                                    .width = options.width,
                                    .height = options.height,
                                    .visible = true,
                                    .debug = true,
                                    .title = "SplatFFD editor: " + options.scene});
    if (!ctx) {
        std::fprintf(stderr, "splatffd view: %s\n", ctx.message().c_str());
        return 1;
    }
    const gfx::FramebufferSize fb = ctx->framebuffer_size();
    const Viewport viewport{fb.width > 0 ? fb.width : options.width,
                            fb.height > 0 ? fb.height : options.height};

    int exit_code = 0;
    {
        ecs::Registry registry;
        registry.set_resource<SceneHooks>(options.scene_hooks);
        if (options.prepare) options.prepare(registry);
        if (Status st = load_scene(registry, options.scene); !st) {
            std::fprintf(stderr, "splatffd view: %s\n", st.message().c_str());
            return 1;
        }
        auto& settings = registry.set_resource<render::RenderSettings>();
        settings.width = viewport.width;
        settings.height = viewport.height;
        settings.quality = options.preview ? render::Quality::preview : render::Quality::hq;
        settings.background = glm::vec3(0.045f, 0.05f, 0.06f);
        settings.aux_outputs = !options.screenshot.empty();  // depth + normals for EXR screenshots
        settings.sprite_path = options.sprite_raster == "cpu"      ? render::SpritePath::cpu
                               : options.sprite_raster == "raster" ? render::SpritePath::raster
                                                                   : render::SpritePath::automatic;
        if (Status st = render::init_render_state(registry); !st) {
            std::fprintf(stderr, "splatffd view: %s\n", st.message().c_str());
            return 1;
        }
        registry.set_resource<OverlayOptions>(OverlayOptions{.line_cache = options.overlay_cache});
        registry.set_resource<UiCacheOptions>(UiCacheOptions{.enabled = options.ui_cache});
        if (Status st = init_lattice_overlay(registry); !st) {
            std::fprintf(stderr, "splatffd view: %s\n", st.message().c_str());
            return 1;
        }

        EditorState& state = setup_editor(registry, viewport);
        state.half_resolution_preview = state.light_overlay_while_moving = gfx::software_rasterizer();
        if (!options.replay.empty()) {
            auto events = load_input_recording(options.replay);
            if (!events) {
                std::fprintf(stderr, "splatffd view: %s\n", events.message().c_str());
                return 1;
            }
            state.replay.emplace(std::move(*events));
        }
        state.record = !options.record.empty();

        ViewSession& session = registry.set_resource<ViewSession>();
        session.options = options;
        // The last folder of the file dialogs, remembered between runs (not for replays: deterministic).
        if (options.replay.empty()) {
            state.settings_file = user_config_file("editor.ini");
            state.last_folder = load_last_folder(state.settings_file);
        }
        session.save_path = options.save_path;
        if (session.save_path.empty()) {
            session.save_path = default_save_path(options.scene);
            // A built-in scene (no folder of its own) is saved in the last folder rather than the current
            // one.
            if (!state.last_folder.empty() && !std::filesystem::path(session.save_path).has_parent_path())
                session.save_path = (std::filesystem::path(state.last_folder) / session.save_path).string();
        }
        // Lattice JSON export/import (ctrl+e / ctrl+i) next to the scene's save, named after the lattice
        // (<folder>/<lattice name>.json); <save>.lattice.json while no lattice is active.
        lattice_fit_settings(registry).json_path =
            std::filesystem::path(session.save_path).replace_extension(".lattice.json").string();
        {
            const std::filesystem::path folder = std::filesystem::path(session.save_path).parent_path();
            lattice_fit_settings(registry).json_folder = folder.empty() ? "." : folder.string();
        }
        session.ui = options.ui && !headless;

        CallbackLink link{&registry, session.ui};
        GLFWwindow* window = ctx->window();
        if (window) {
            glfwSetWindowUserPointer(window, &link);
            // Ours first; ImGui's backend chains to them (install_callbacks = true).
            glfwSetCursorPosCallback(window, on_cursor);
            glfwSetMouseButtonCallback(window, on_button);
            glfwSetScrollCallback(window, on_scroll);
            glfwSetKeyCallback(window, on_key);
        }
        if (session.ui) {
            IMGUI_CHECKVERSION();
            ImGui::CreateContext();
            // The layout the user chose (collapsed panels) is remembered in a per-user config folder, never
            // next to the user's files; replays start from the default layout and leave the file alone.
            static std::string ini_path;  // ImGui keeps the pointer until DestroyContext
            ini_path = options.replay.empty() ? user_config_file("imgui.ini") : std::string();
            ImGui::GetIO().IniFilename = ini_path.empty() ? nullptr : ini_path.c_str();
            ImGui::StyleColorsDark();
            // Opaque panels (the dark style's are 94% opaque): their backgrounds are clears of one colour
            // (panel_backgrounds()), whatever lies under them.
            ImGui::GetStyle().Colors[ImGuiCol_WindowBg].w = 1.0f;
            ImGui_ImplGlfw_InitForOpenGL(window, true);
            ImGui_ImplOpenGL3_Init("#version 450");
            // Nearest sampling of the font atlas: the default font is a pixel font drawn 1:1 at whole
            // pixels and every panel background samples the atlas's white texel, so bilinear filtering
            // changed nothing on screen but cost a third of the panels' fill on a CPU rasteriser. Lines
            // are then anti-aliased by geometry instead of by the atlas's baked (filtered) line texture.
            ImGui::GetIO().Fonts->Flags |= ImFontAtlasFlags_NoBakedLines;
            ImGui_ImplOpenGL3_CreateDeviceObjects();  // builds the atlas texture now, so it can be set
            const auto atlas = GLuint(reinterpret_cast<std::uintptr_t>(ImGui::GetIO().Fonts->TexID));
            glTextureParameteri(atlas, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
            glTextureParameteri(atlas, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        }

        // Unsynchronised, the GL work of one system is charged to whichever later system first waits for
        // it (display, blit, swap); --sync-timing finishes the GL queue around every system instead.
        profiling::Profiler profiler(
            {.gpu = options.sync_timing ? profiling::GpuTiming::sync : profiling::GpuTiming::none,
             .keep_frames = true});
        profiler.attach(schedule, registry);
        // Replays and fixed frame counts run on a fixed 1/60 s clock (frame k = time k/60, deterministic).
        Clock clock = (!options.replay.empty() || options.frames > 0 || headless)
                          ? Clock(ClockSettings{.fixed_dt = 1.0 / 60.0})
                          : app::make_clock(&*ctx);
        const app::RunResult run = app::run(registry, schedule, clock, &*ctx, {.max_frames = options.frames});
        log::info("view: ", run.frames, " frames in ", run.seconds, " s");
        if (const OverlayCacheStats c = overlay_cache_stats(registry); c.rebuilt + c.reused > 0)
            log::info("view: lattice edges cached in ", c.rebuilt + c.reused, " frames (", c.rebuilt,
                      " drew the cache again), drawn directly in ", c.direct, "; ", c.cached_edges,
                      " cached and ", c.live_edges, " live edges over the cached frames");
        if (const UiCacheStats u = ui_cache_stats(registry); u.frames + u.direct_frames > 0)
            log::info("view: panels through the cache in ", u.frames, " frames (", u.reused,
                      " copied as they were, ", u.cached, " drawn into it, ", u.drawn,
                      " drawn directly), every panel drawn directly in ", u.direct_frames);

        if (!options.screenshot.empty()) {
            if (Status st = write_screenshot(registry, options.screenshot); !st) {
                std::fprintf(stderr, "splatffd view: %s\n", st.message().c_str());
                exit_code = 1;
            }
        }
        if (!options.record.empty()) {
            if (Status st = write_file_atomic(options.record, format_input_recording(state.recorded)); !st) {
                std::fprintf(stderr, "splatffd view: %s\n", st.message().c_str());
                exit_code = 1;
            }
        }
        // Frame times: all frames, and the frames in which a stretch/twist drag was live.
        std::vector<double> all, drag;
        for (const auto& f : profiler.frames()) {
            std::fprintf(stderr, "F %llu %d %.1f:", (unsigned long long)f.frame,
                         int(f.frame < session.dragging.size() && session.dragging[f.frame]), f.total_ms);
            for (const auto& sc : f.scopes)
                if (sc.cpu_ms > 0.8)
                    std::fprintf(stderr, " %s=%.1f", profiler.name(sc.name).c_str(), sc.cpu_ms);
            std::fprintf(stderr, "\n");
        }
        for (const auto& f : profiler.frames()) {
            if (f.frame == 0) continue;  // first frame: uploads and shader warm-up
            all.push_back(f.total_ms);
            if (f.frame < session.dragging.size() && session.dragging[f.frame]) drag.push_back(f.total_ms);
        }
        std::fprintf(stderr,
                     "view: frame ms p50 %.2f p95 %.2f (n=%zu); while dragging p50 %.2f p95 %.2f (n=%zu)\n",
                     percentile(all, 0.5), percentile(all, 0.95), all.size(), percentile(drag, 0.5),
                     percentile(drag, 0.95), drag.size());
        // Per system (and per named GL pass), median CPU time over the drag frames (where the time of a drag
        // goes; with --sync-timing each includes its own GL work).
        std::string per_system, per_pass;
        for (const auto kind : {profiling::ScopeKind::system, profiling::ScopeKind::pass}) {
            std::string& list = kind == profiling::ScopeKind::system ? per_system : per_pass;
            std::vector<std::pair<std::string, std::vector<double>>> rows;
            for (const auto& f : profiler.frames()) {
                if (f.frame == 0 || f.frame >= session.dragging.size() || !session.dragging[f.frame])
                    continue;
                for (const auto& sc : f.scopes) {
                    if (sc.kind != kind) continue;
                    const std::string& name = profiler.name(sc.name);
                    auto it = std::find_if(rows.begin(), rows.end(),
                                           [&](const auto& r) { return r.first == name; });
                    if (it == rows.end()) rows.emplace_back(name, std::vector<double>{}), it = rows.end() - 1;
                    it->second.push_back(sc.cpu_ms);
                }
            }
            for (const auto& [name, ms] : rows) {
                if (kind == profiling::ScopeKind::system)
                    std::fprintf(stderr, "view:   while dragging, %-16s p50 %.2f ms\n", name.c_str(),
                                 percentile(ms, 0.5));
                list += (list.empty() ? "" : ", ") + std::string("\"") + name +
                        "\": " + std::to_string(percentile(ms, 0.5));
            }
        }
        if (!options.timing_json.empty()) {
            std::string json = "{\n  \"renderer\": \"" + ctx->renderer() + "\",\n  \"timing\": \"" +
                               (options.sync_timing ? "sync" : "unsynchronised") +
                               "\",\n  \"frames\": " + std::to_string(all.size()) +
                               ",\n  \"frame_ms_p50\": " + std::to_string(percentile(all, 0.5)) +
                               ",\n  \"frame_ms_p95\": " + std::to_string(percentile(all, 0.95)) +
                               ",\n  \"drag_frames\": " + std::to_string(drag.size()) +
                               ",\n  \"drag_frame_ms_p50\": " + std::to_string(percentile(drag, 0.5)) +
                               ",\n  \"drag_frame_ms_p95\": " + std::to_string(percentile(drag, 0.95)) +
                               ",\n  \"drag_system_ms_p50\": {" + per_system + "}" +
                               ",\n  \"drag_pass_ms_p50\": {" + per_pass + "}\n}\n";
            if (Status st = write_file_atomic(options.timing_json, json); !st)
                std::fprintf(stderr, "splatffd view: %s\n", st.message().c_str());
        }
        release_ui_cache(registry);
        if (session.ui) {
            ImGui_ImplOpenGL3_Shutdown();
            ImGui_ImplGlfw_Shutdown();
            ImGui::DestroyContext();
        }
        if (window) {
            glfwSetWindowUserPointer(window, nullptr);
            glfwSetCursorPosCallback(window, nullptr);
            glfwSetMouseButtonCallback(window, nullptr);
            glfwSetScrollCallback(window, nullptr);
            glfwSetKeyCallback(window, nullptr);
        }
        release_lattice_overlay(registry);
        render::release_render_state(registry);
        registry.erase_resource<app::PresentSource>();
    }  // registry (and any GL state it still holds) goes before the context
    return exit_code;
}

}  // namespace sffd::editor
