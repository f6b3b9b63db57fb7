// findmug/daemon/object_library.hpp — the taught objects the daemon looks
// for: every *.fmo file of one folder (daemon.objects_dir), kept current.
//
//   * Loading: each file through loadObjectModel (objects/object_model.hpp),
//     which checks every field. A corrupt file, or one whose name is already
//     taken by another file (two "mug"s: which one is meant?), is refused: it
//     goes to refusals() with the file name and the reason, for the status
//     message and the log, and the daemon keeps running with the others.
//   * refresh(): cheap enough to call every few seconds. The folder is listed
//     and each file's size and modification time compared with what was
//     loaded: only new or changed files are read, removed ones are dropped
//     (a refused file that is fixed is read again; one that stays as it was
//     stays refused without being read again). Files are written by
//     saveObjectModel through a rename, so a file is never seen half-written.
//   * models(): an immutable snapshot, shared: a frame thread takes it once
//     per frame and keeps it while a refresh on another thread replaces it.
//
// Thread safety: refresh() calls are serialised among themselves; models(),
// refusals() and the counters may be called from any thread at any time.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "findmug/objects/object_model.hpp"

namespace findmug::daemon {

struct ObjectFileRefusal {
  std::string file;    // path of the refused file
  std::string reason;  // the findmug::Error's message
};

struct ObjectLibraryChange {
  std::vector<std::string> loaded;         // files read and accepted (new or changed)
  std::vector<std::string> dropped;        // files removed from the folder, or now refused
  std::vector<ObjectFileRefusal> refused;  // files read and refused in this refresh
  bool changed() const { return !loaded.empty() || !dropped.empty() || !refused.empty(); }
};

class ObjectLibrary {
 public:
  using Models = std::shared_ptr<const std::vector<ObjectModel>>;

  // Does not read the folder yet (call refresh()). An empty `dir`: no objects.
  explicit ObjectLibrary(std::string dir);

  // Re-scans the folder (see above). A missing or unreadable folder counts as
  // empty and is reported as a refusal of the folder itself. Never throws
  // findmug::Error for a bad file.
  ObjectLibraryChange refresh();

  // The accepted models, sorted by name.
  Models models() const;
  // The files refused as of the last refresh, sorted by file name.
  std::vector<ObjectFileRefusal> refusals() const;
  const std::string& dir() const { return dir_; }
  std::uint64_t fileReads() const;  // files read since construction (for the tests and status)

 private:
  struct FileStamp {
    std::uintmax_t size = 0;
    std::filesystem::file_time_type mtime{};
    bool operator==(const FileStamp&) const = default;
  };
  struct Entry {
    FileStamp stamp;
    std::shared_ptr<const ObjectModel> model;  // null when refused
    std::string reason;                        // why refused
  };

  void publish(const std::map<std::string, Entry>& entries, std::vector<ObjectFileRefusal> extra);

  const std::string dir_;
  std::mutex refresh_mutex_;              // one refresh at a time
  std::map<std::string, Entry> entries_;  // by path; guarded by refresh_mutex_
  mutable std::mutex snapshot_mutex_;     // guards the three below
  Models models_;
  std::vector<ObjectFileRefusal> refusals_;
  std::uint64_t file_reads_ = 0;
};

}  // namespace findmug::daemon
