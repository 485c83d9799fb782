// The README's frame table, generated from the schedule's declarations (engine.cpp), so the document
// says what the check (SFFD_CHECK_ACCESS) enforces.
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "systems/engine/engine.h"

namespace sffd {
namespace {

std::string type_list(const std::vector<ecs::TypeRef>& types) {
    if (types.empty()) return "none";
    std::set<std::string> sorted;
    for (const ecs::TypeRef& t : types) {
        std::string quoted(1, '`');
        quoted.append(t.name).push_back('`');
        // Template arguments keep the project's namespace the type name drops at its front.
        for (std::size_t at; (at = quoted.find("sffd::")) != std::string::npos;) quoted.erase(at, 6);
        sorted.insert(std::move(quoted));
    }
    std::string out;
    for (const std::string& name : sorted) out += (out.empty() ? "" : ", ") + name;
    return out;
}

bool runs_in(const Schedule& s, Phase phase, const std::string& name) {
    for (const Schedule::Entry& e : s.systems(phase))
        if (e.name == name) return true;
    return false;
}

}  // namespace

std::string frame_table_markdown() {
    const Schedule all = make_engine_schedule({.present = true, .editor = true});
    const Schedule plain = make_engine_schedule({.present = true, .editor = false});
    std::string out =
        "| # | phase | system | reads | writes |\n"
        "|---|---|---|---|---|\n";
    for (std::size_t p = 0; p < phase_count; ++p) {
        const auto phase = static_cast<Phase>(p);
        for (const Schedule::Entry& e : all.systems(phase)) {
            const std::string only = runs_in(plain, phase, e.name) ? "" : " (editor only)";
            const bool declared = e.access.declared();
            const std::string undeclared = "not declared (unchecked)";
            out += "| " + std::to_string(p + 1) + " | " + phase_name(phase) + " | `" + e.name + "`" + only +
                   " | " + (declared ? type_list(e.access.read_types()) : undeclared) + " | " +
                   (declared ? type_list(e.access.write_types()) : undeclared) + " |\n";
        }
    }
    return out;
}

}  // namespace sffd
