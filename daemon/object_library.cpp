// The daemon's taught objects (object_library.hpp): a folder of .fmo files
// read through the core's checked loader, re-read only where a file changed.
#include "findmug/daemon/object_library.hpp"

#include <algorithm>
#include <set>
#include <utility>

#include "findmug/common/error.hpp"

namespace findmug::daemon {

namespace fs = std::filesystem;

ObjectLibrary::ObjectLibrary(std::string dir)
    : dir_(std::move(dir)), models_(std::make_shared<const std::vector<ObjectModel>>()) {}

ObjectLibraryChange ObjectLibrary::refresh() {
  std::lock_guard<std::mutex> lock(refresh_mutex_);
  ObjectLibraryChange change;
  std::vector<ObjectFileRefusal> folder_refusal;
  std::set<std::string> present;
  std::uint64_t reads = 0;
  if (!dir_.empty()) {
    std::error_code ec;
    fs::directory_iterator it(dir_, ec);
    if (ec) folder_refusal.push_back({dir_, "cannot read the folder: " + ec.message()});
    for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
      const fs::path& path = it->path();
      std::error_code file_ec;
      if (path.extension() != ".fmo" || !it->is_regular_file(file_ec)) continue;
      FileStamp stamp;
      stamp.size = fs::file_size(path, file_ec);
      if (!file_ec) stamp.mtime = fs::last_write_time(path, file_ec);
      if (file_ec) continue;  // gone between the listing and now: as if not listed
      const std::string name = path.string();
      present.insert(name);
      const auto known = entries_.find(name);
      if (known != entries_.end() && known->second.stamp == stamp) continue;
      Entry entry;
      entry.stamp = stamp;
      ++reads;
      try {
        entry.model = std::make_shared<const ObjectModel>(loadObjectModel(name));
        change.loaded.push_back(name);
      } catch (const Error& e) {
        entry.reason = e.what();
        change.refused.push_back({name, entry.reason});
      }
      entries_[name] = std::move(entry);
    }
    if (ec && folder_refusal.empty()) {
      folder_refusal.push_back({dir_, "cannot list the folder: " + ec.message()});
    }
  }
  for (auto it = entries_.begin(); it != entries_.end();) {
    if (present.count(it->first) != 0) {
      ++it;
      continue;
    }
    change.dropped.push_back(it->first);
    it = entries_.erase(it);
  }
  {
    std::lock_guard<std::mutex> snapshot(snapshot_mutex_);
    file_reads_ += reads;
  }
  publish(entries_, std::move(folder_refusal));
  return change;
}

// The snapshot: the accepted models by name; of two files holding one name,
// the first by path is taken and the other refused (it is taken again,
// without a read, once the first is gone).
void ObjectLibrary::publish(const std::map<std::string, Entry>& entries,
                            std::vector<ObjectFileRefusal> refusals) {
  std::map<std::string, std::string> path_of_name;
  std::vector<const ObjectModel*> accepted;
  for (const auto& [path, entry] : entries) {
    if (!entry.model) {
      refusals.push_back({path, entry.reason});
      continue;
    }
    const auto [taken, inserted] = path_of_name.emplace(entry.model->name, path);
    if (!inserted) {
      refusals.push_back(
          {path, "object name \"" + entry.model->name + "\" is already taken by " + taken->second});
      continue;
    }
    accepted.push_back(entry.model.get());
  }
  std::sort(accepted.begin(), accepted.end(),
            [](const ObjectModel* a, const ObjectModel* b) { return a->name < b->name; });
  auto models = std::make_shared<std::vector<ObjectModel>>();
  models->reserve(accepted.size());
  for (const ObjectModel* m : accepted) models->push_back(*m);
  std::sort(refusals.begin(), refusals.end(),
            [](const ObjectFileRefusal& a, const ObjectFileRefusal& b) { return a.file < b.file; });
  std::lock_guard<std::mutex> lock(snapshot_mutex_);
  models_ = std::move(models);
  refusals_ = std::move(refusals);
}

ObjectLibrary::Models ObjectLibrary::models() const {
  std::lock_guard<std::mutex> lock(snapshot_mutex_);
  return models_;
}

std::vector<ObjectFileRefusal> ObjectLibrary::refusals() const {
  std::lock_guard<std::mutex> lock(snapshot_mutex_);
  return refusals_;
}

std::uint64_t ObjectLibrary::fileReads() const {
  std::lock_guard<std::mutex> lock(snapshot_mutex_);
  return file_reads_;
}

}  // namespace findmug::daemon
