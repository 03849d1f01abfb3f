// Undo and redo of the viewer's edits (Ctrl+Z, Ctrl+Shift+Z). Every state is the whole look as JSON
// (scene + display), so undo restores exactly what was shown, whatever the edit was. Edits made in
// one gesture (a slider drag, a camera tumble, a burst of wheel steps) form one group: one undo step.
// Headless, so tests drive it without a window.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace candela {

class EditHistory {
 public:
  explicit EditHistory(size_t maxSteps = 500) : maxSteps_(maxSteps) {}

  // Starts over from `state` (a scene was opened): nothing to undo.
  void reset(const nlohmann::json& state) {
    states_ = {state};
    current_ = 0;
    group_.clear();
  }
  // Replaces the current state without a step (an automatic change such as auto exposure on open).
  void amend(const nlohmann::json& state) {
    if (!states_.empty()) states_[current_] = state;
  }
  // An automatic choice that holds for the whole document, not for one step (auto exposure on open):
  // every state with no value at `pointer` takes `value`. An edit made before the choice came is
  // undone without undoing the choice with it, and a state that has its own value keeps it.
  void fillEverywhere(const nlohmann::json::json_pointer& pointer, const nlohmann::json& value) {
    for (auto& state : states_)
      if (!state.contains(pointer)) state[pointer] = value;
  }
  // Records the state after an edit. An edit in the same open group as the previous one replaces it;
  // a state equal to the current one records nothing. Any redo steps are dropped.
  void record(const nlohmann::json& state, const std::string& group = "") {
    if (states_.empty()) return reset(state);
    if (state == states_[current_]) return;
    states_.resize(current_ + 1);
    if (!group.empty() && group == group_ && current_ > 0) {
      states_[current_] = state;
      return;
    }
    states_.push_back(state);
    ++current_;
    group_ = group;
    if (states_.size() > maxSteps_) {
      states_.erase(states_.begin());
      --current_;
    }
  }
  // The current state could not be built, and the scene went back to `state`: the failed state
  // leaves the history, so that undo and redo never replay it. Its step goes when the step before
  // it is `state` (the usual case: the edit just made failed); otherwise it becomes `state`.
  void revertCurrent(const nlohmann::json& state) {
    if (states_.empty()) return reset(state);
    group_.clear();
    if (current_ > 0 && states_[current_ - 1] == state) {
      states_.erase(states_.begin() + static_cast<std::ptrdiff_t>(current_));
      --current_;
    } else {
      states_[current_] = state;
    }
  }
  // Ends the open group: the next edit is a new step even in the same group (the gesture ended).
  void endGroup() { group_.clear(); }

  bool canUndo() const { return current_ > 0; }
  bool canRedo() const { return current_ + 1 < states_.size(); }
  std::optional<nlohmann::json> undo() {
    if (!canUndo()) return std::nullopt;
    group_.clear();
    return states_[--current_];
  }
  std::optional<nlohmann::json> redo() {
    if (!canRedo()) return std::nullopt;
    group_.clear();
    return states_[++current_];
  }
  size_t undoSteps() const { return current_; }
  size_t redoSteps() const { return states_.size() - 1 - current_; }

 private:
  std::vector<nlohmann::json> states_;
  size_t current_ = 0;
  std::string group_;
  size_t maxSteps_;
};

}  // namespace candela
