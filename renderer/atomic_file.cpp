#include "atomic_file.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <unistd.h>

namespace candela {

namespace fs = std::filesystem;

namespace {

std::string temporaryPath(const fs::path& target) {
  static std::atomic<unsigned> counter{0};
  const std::string name = "." + target.stem().string() + ".partial-" + std::to_string(::getpid()) + "-" +
                           std::to_string(counter.fetch_add(1)) + target.extension().string();
  return (target.parent_path() / name).string();
}

// The written bytes reach the disk before the rename makes them the file: after a crash the final
// name holds the old file or the new one, never an empty one.
void flushToDisk(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw std::runtime_error("cannot reopen the written file (" + std::string(std::strerror(errno)) + ")");
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) throw std::runtime_error("cannot flush to disk (" + std::string(std::strerror(err)) + ")");
}

}  // namespace

void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write) {
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), ec);
    if (ec) throw std::runtime_error(path + ": cannot create its folder (" + ec.message() + ")");
  }
  const std::string temporary = temporaryPath(target);
  try {
    write(temporary);
    if (fs::file_size(temporary, ec) == 0 && !ec)
      throw std::runtime_error("nothing was written");
    flushToDisk(temporary);
    fs::rename(temporary, target, ec);
    if (ec) throw std::runtime_error("cannot replace it (" + ec.message() + ")");
  } catch (const std::exception& e) {
    fs::remove(temporary, ec);
    const std::string what = e.what();
    // Writers name the temporary file; the user knows the final one.
    std::string message = what;
    for (size_t at = message.find(temporary); at != std::string::npos; at = message.find(temporary)) message.replace(at, temporary.size(), path);
    throw std::runtime_error(message.rfind(path, 0) == 0 ? message : path + ": " + message);
  }
}

void writeTextAtomically(const std::string& path, const std::string& text) {
  writeAtomically(path, [&](const std::string& temporary) {
    std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(temporary.c_str(), "wb"), &std::fclose);
    if (!f) throw std::runtime_error("cannot open for writing (" + std::string(std::strerror(errno)) + ")");
    if (!text.empty() && std::fwrite(text.data(), 1, text.size(), f.get()) != text.size())
      throw std::runtime_error("cannot write (" + std::string(std::strerror(errno)) + ")");
    if (std::fflush(f.get()) != 0) throw std::runtime_error("cannot write (" + std::string(std::strerror(errno)) + ")");
    FILE* raw = f.release();
    if (std::fclose(raw) != 0) throw std::runtime_error("cannot write (" + std::string(std::strerror(errno)) + ")");
  });
}

}  // namespace candela
