#include "runtime/gfx/shader.h"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "runtime/core/file_io.h"
#include "runtime/core/log.h"
#include "runtime/core/paths.h"

namespace sffd::gfx {
namespace fs = std::filesystem;

namespace {

std::string_view trim_left(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    return s;
}

// "#  include" -> true, with `rest` set to what follows the directive name.
bool is_directive(std::string_view line, std::string_view name, std::string_view* rest = nullptr) {
    line = trim_left(line);
    if (line.empty() || line.front() != '#') return false;
    line = trim_left(line.substr(1));
    if (line.substr(0, name.size()) != name) return false;
    line.remove_prefix(name.size());
    if (!line.empty() && line.front() != ' ' && line.front() != '\t' && line.front() != '"' &&
        line.front() != '<' && line.front() != '\r')
        return false;  // e.g. "#includes"
    if (rest) *rest = trim_left(line);
    return true;
}

Result<std::string> read_text(const fs::path& path) {
    auto text = read_file(path, 16u << 20);  // runtime/core/file_io.h: regular files only
    if (!text) return make_error(path.string() + ": cannot open shader file (" + text.message() + ")");
    return text;
}

std::vector<std::string_view> split_lines(std::string_view text) {
    std::vector<std::string_view> lines;
    std::size_t start = 0;
    while (start <= text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string_view::npos) {
            if (start < text.size()) lines.push_back(text.substr(start));
            break;
        }
        std::string_view line = text.substr(start, end - start);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        lines.push_back(line);
        start = end + 1;
    }
    return lines;
}

class Preprocessor {
public:
    Preprocessor(fs::path root, const Defines& defines) : m_root(std::move(root)), m_defines(defines) {}

    Result<PreprocessedSource> run(const fs::path& main) {
        const fs::path path = (main.is_absolute() ? main : m_root / main).lexically_normal();
        if (Status s = expand(path, true); !s) return s.error();
        return PreprocessedSource{std::move(m_out), std::move(m_files)};
    }

private:
    int file_id(const fs::path& path) {
        auto it = std::find(m_files.begin(), m_files.end(), path);
        if (it != m_files.end()) return int(it - m_files.begin());
        m_files.push_back(path);
        return int(m_files.size() - 1);
    }

    Status expand(const fs::path& path, bool is_main) {
        Result<std::string> text = read_text(path);
        if (!text) return text.error();
        const int id = file_id(path);
        m_stack.push_back(path);
        const std::vector<std::string_view> lines = split_lines(*text);
        bool seen_version = !is_main;
        bool in_block_comment = false;
        for (std::size_t i = 0; i < lines.size(); ++i) {
            const std::string_view line = lines[i];
            const std::size_t line_no = i + 1;
            const bool starts_in_comment = in_block_comment;
            // Track /* */ so a commented-out #include is left alone (line comments are checked below).
            for (std::size_t c = 0; c + 1 < line.size(); ++c) {
                if (!in_block_comment && line[c] == '/' && line[c + 1] == '/') break;
                if (!in_block_comment && line[c] == '/' && line[c + 1] == '*') in_block_comment = true, ++c;
                else if (in_block_comment && line[c] == '*' && line[c + 1] == '/')
                    in_block_comment = false, ++c;
            }
            std::string_view rest;
            if (starts_in_comment) {
                emit(line);
            } else if (is_directive(line, "version")) {
                if (!is_main)
                    return fail(log::str(path.string(), ":", line_no, ": #version in an included file"));
                emit(line);
                for (const auto& [name, value] : m_defines)
                    emit(log::str("#define ", name, value.empty() ? "" : " ", value));
                emit(log::str("#line ", line_no + 1, " ", id));
                seen_version = true;
            } else if (is_directive(line, "pragma", &rest) && trim_left(rest).substr(0, 4) == "once") {
                m_once.push_back(path);
                emit("");
            } else if (is_directive(line, "include", &rest)) {
                const char open = rest.empty() ? '\0' : rest.front();
                const char close = open == '<' ? '>' : '"';
                const std::size_t end = rest.find(close, 1);
                if ((open != '"' && open != '<') || end == std::string_view::npos)
                    return fail(log::str(path.string(), ":", line_no,
                                         ": malformed #include (expected #include \"file\")"));
                const std::string name(rest.substr(1, end - 1));
                fs::path target;
                std::error_code ec;
                for (const fs::path& candidate : {path.parent_path() / name, m_root / name})
                    if (fs::is_regular_file(candidate, ec)) {
                        target = candidate.lexically_normal();
                        break;
                    }
                if (target.empty())
                    return fail(log::str(path.string(), ":", line_no, ": cannot open include \"", name,
                                         "\" (looked in ", path.parent_path().string(), " and ",
                                         m_root.string(), ")"));
                if (std::find(m_stack.begin(), m_stack.end(), target) != m_stack.end()) {
                    std::string chain;
                    for (const fs::path& p : m_stack) chain += p.filename().string() + " -> ";
                    return fail(log::str(path.string(), ":", line_no, ": #include cycle: ", chain,
                                         target.filename().string()));
                }
                if (std::find(m_once.begin(), m_once.end(), target) != m_once.end()) {
                    emit("");
                    continue;
                }
                emit(log::str("#line 1 ", file_id(target)));
                if (Status s = expand(target, false); !s) return s;
                emit(log::str("#line ", line_no + 1, " ", id));
            } else {
                emit(line);
            }
        }
        if (!seen_version) return fail(path.string() + ": missing #version on the first line");
        m_stack.pop_back();
        return {};
    }

    Status fail(std::string message) { return make_error(std::move(message)); }

    void emit(std::string_view line) {
        m_out.append(line);
        m_out.push_back('\n');
    }

    fs::path m_root;
    const Defines& m_defines;
    std::string m_out;
    std::vector<fs::path> m_files;
    std::vector<fs::path> m_stack;
    std::vector<fs::path> m_once;
};

const char* stage_name(GLenum stage) {
    switch (stage) {
        case GL_VERTEX_SHADER: return "vert";
        case GL_FRAGMENT_SHADER: return "frag";
        case GL_GEOMETRY_SHADER: return "geom";
        case GL_TESS_CONTROL_SHADER: return "tesc";
        case GL_TESS_EVALUATION_SHADER: return "tese";
        case GL_COMPUTE_SHADER: return "comp";
        default: return "shader";
    }
}

std::string trim_trailing(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ' || s.back() == '\0'))
        s.pop_back();
    return s;
}

}  // namespace

Result<PreprocessedSource> preprocess_shader(const fs::path& root, const fs::path& path,
                                             const Defines& defines) {
    return Preprocessor(root, defines).run(path);
}

namespace {

// Parses "<id>:<line>[(<col>)]:" (Mesa, glslang) or "<id>(<line>) :" (NVIDIA) at the start of `s`; on
// success `s` is left at the message.
bool parse_log_location(std::string_view& s, std::size_t& id, std::size_t& line) {
    auto number = [](std::string_view& t, std::size_t& out) {
        std::size_t n = 0, v = 0;
        while (n < t.size() && t[n] >= '0' && t[n] <= '9' && n < 9) v = v * 10 + std::size_t(t[n++] - '0');
        if (n == 0) return false;
        out = v;
        t.remove_prefix(n);
        return true;
    };
    std::string_view t = trim_left(s);
    for (std::string_view prefix : {"ERROR: ", "WARNING: "})
        if (t.substr(0, prefix.size()) == prefix) t.remove_prefix(prefix.size());
    if (!number(t, id) || t.empty()) return false;
    if (t.front() == ':') {
        t.remove_prefix(1);
        if (!number(t, line)) return false;
        if (!t.empty() && t.front() == '(') {
            const std::size_t close = t.find(')');
            if (close == std::string_view::npos) return false;
            t.remove_prefix(close + 1);
        }
        if (t.empty() || t.front() != ':') return false;
    } else if (t.front() == '(') {
        t.remove_prefix(1);
        if (!number(t, line) || t.empty() || t.front() != ')') return false;
        t = trim_left(t.substr(1));
        if (t.empty() || t.front() != ':') return false;
    } else {
        return false;
    }
    t.remove_prefix(1);
    if (!t.empty() && t.front() == ' ') t.remove_prefix(1);
    s = t;
    return true;
}

}  // namespace

std::string map_shader_log(std::string_view log_text, const std::vector<fs::path>& files) {
    std::string out;
    for (std::string_view line : split_lines(log_text)) {
        if (line.empty()) continue;
        std::string_view message = line;
        std::size_t id = 0, line_no = 0;
        if (parse_log_location(message, id, line_no)) {
            const std::string file = id < files.size() ? files[id].string() : log::str("<source ", id, ">");
            out += log::str(file, ":", line_no, ": ", message, "\n");
        } else {
            out.append(line).push_back('\n');
        }
    }
    return trim_trailing(std::move(out));
}

Result<Program> load_program(const fs::path& root, const std::vector<ShaderSource>& sources,
                             std::string_view label, const Defines& defines) {
    if (sources.empty()) return make_error(log::str("load_program(", label, "): no shader stages given"));
    std::vector<Shader> shaders;
    for (const ShaderSource& source : sources) {
        Result<PreprocessedSource> pre = preprocess_shader(root, source.path, defines);
        if (!pre) return pre.error();
        Shader shader = Shader::create(log::str(label, ".", stage_name(source.stage)), source.stage);
        const char* text = pre->text.c_str();
        const auto length = static_cast<GLint>(pre->text.size());
        glShaderSource(shader.id(), 1, &text, &length);
        glCompileShader(shader.id());
        GLint ok = 0, log_length = 0;
        glGetShaderiv(shader.id(), GL_COMPILE_STATUS, &ok);
        glGetShaderiv(shader.id(), GL_INFO_LOG_LENGTH, &log_length);
        std::string info(std::size_t(std::max(log_length, 1)), '\0');
        if (log_length > 1) glGetShaderInfoLog(shader.id(), log_length, nullptr, info.data());
        const std::string mapped = map_shader_log(trim_trailing(info), pre->files);
        if (!ok) {
            if (mapped.empty())
                return make_error(pre->files[0].string() + ": compile failed (the driver gave no log)");
            return make_error(mapped);
        }
        if (!mapped.empty()) log::warn(mapped);
        shaders.push_back(std::move(shader));
    }
    Program program = Program::create(label);
    for (const Shader& s : shaders) glAttachShader(program.id(), s.id());
    glLinkProgram(program.id());
    for (const Shader& s : shaders) glDetachShader(program.id(), s.id());
    GLint ok = 0, log_length = 0;
    glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
    glGetProgramiv(program.id(), GL_INFO_LOG_LENGTH, &log_length);
    std::string info(std::size_t(std::max(log_length, 1)), '\0');
    if (log_length > 1) glGetProgramInfoLog(program.id(), log_length, nullptr, info.data());
    info = trim_trailing(info);
    if (!ok) {
        std::string files;
        for (const ShaderSource& s : sources) files += (files.empty() ? "" : ", ") + s.path;
        return make_error(log::str("load_program(", label, "): link failed (", files, "): ", info));
    }
    if (!info.empty()) log::debug("load_program(", label, "): ", info);
    return program;
}

Result<Program> load_program(const std::vector<ShaderSource>& sources, std::string_view label,
                             const Defines& defines) {
    return load_program(paths::shader_dir(), sources, label, defines);
}

Result<Program> load_compute_program(const std::string& path, std::string_view label,
                                     const Defines& defines) {
    return load_program(paths::shader_dir(), {{GL_COMPUTE_SHADER, path}}, label, defines);
}

}  // namespace sffd::gfx
