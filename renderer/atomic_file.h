// Every output Candela writes (EXR, PNG, CSV, SVG, HTML, JSON) goes through here: the file is
// written under a temporary name in the target folder, flushed to disk, and renamed over the final
// name only when complete. A failure (a full disk, a killed process, a bad path) removes the
// temporary file and leaves whatever was under the final name as it was; a reader never sees a
// partial file there.
#pragma once

#include <functional>
#include <string>

namespace candela {

// Calls `write` with a temporary path beside `path` (same folder, same extension, so that writers
// choosing a format by extension still do), then makes it `path`. Throws std::runtime_error naming
// `path` when the file cannot be written or replaced; the folder is created when missing.
void writeAtomically(const std::string& path, const std::function<void(const std::string& temporary)>& write);

// `text` as the whole of `path`, atomically.
void writeTextAtomically(const std::string& path, const std::string& text);

}  // namespace candela
