#include "systems/editor/undo_stack.h"

namespace sffd::editor {

bool UndoStack::push(std::unique_ptr<Command> command) {
    if (!command || command->empty()) return false;
    m_commands.resize(m_next);  // a new step after undo forgets the undone future
    m_commands.push_back(std::move(command));
    if (m_limit > 0 && m_commands.size() > m_limit) m_commands.erase(m_commands.begin());
    m_next = m_commands.size();
    return true;
}

std::size_t UndoStack::bytes() const {
    std::size_t n = sizeof(*this) + m_commands.capacity() * sizeof(m_commands[0]);
    for (const auto& c : m_commands) n += c->bytes();
    n += m_map.size() * (sizeof(std::uint64_t) + sizeof(ecs::Entity) + 2 * sizeof(void*));
    return n;
}

bool UndoStack::undo(ecs::Registry& registry) {
    if (!can_undo()) return false;
    m_commands[--m_next]->undo(registry, m_map);
    return true;
}

bool UndoStack::redo(ecs::Registry& registry) {
    if (!can_redo()) return false;
    m_commands[m_next++]->redo(registry, m_map);
    return true;
}

}  // namespace sffd::editor
