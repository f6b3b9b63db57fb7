// Unit tests of the daemon's concurrency building blocks: the bounded queue
// and its drop policy, the reorder buffer, stages in sequential and threaded
// mode, the status statistics, the watchdog gate and the daemon config.
// No timed assertions: threads are synchronised with latches/flags only.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/daemon/bounded_queue.hpp"
#include "findmug/daemon/daemon_config.hpp"
#include "findmug/daemon/reorder_buffer.hpp"
#include "findmug/daemon/service.hpp"
#include "findmug/daemon/stage.hpp"
#include "findmug/daemon/stats.hpp"
#include "findmug/settings/config.hpp"
#include "program_settings.hpp"
#include "test_data.hpp"

namespace findmug::daemon {
namespace {

using namespace std::chrono_literals;

TEST(BoundedQueue, DropOldestKeepsTheNewestAndCountsDrops) {
  BoundedQueue<int> q(3, DropPolicy::DropOldest);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(q.push(i), PushResult::Accepted);
  std::optional<int> evicted;
  EXPECT_EQ(q.push(3, &evicted), PushResult::AcceptedDroppedOldest);
  ASSERT_TRUE(evicted);
  EXPECT_EQ(*evicted, 0);
  EXPECT_EQ(q.push(4), PushResult::AcceptedDroppedOldest);
  EXPECT_EQ(q.droppedCount(), 2u);
  EXPECT_EQ(q.size(), 3u);
  // The survivors are the newest three, in order, with consecutive tickets.
  for (int expected = 2, ticket = 0; expected <= 4; ++expected, ++ticket) {
    auto p = q.pop();
    ASSERT_TRUE(p);
    EXPECT_EQ(p->value, expected);
    EXPECT_EQ(p->ticket, static_cast<std::uint64_t>(ticket));
  }
}

TEST(BoundedQueue, CloseDrainsThenEnds) {
  BoundedQueue<int> q(2, DropPolicy::DropOldest);
  q.push(1);
  q.close();
  EXPECT_EQ(q.push(2), PushResult::Closed);
  auto p = q.pop();
  ASSERT_TRUE(p);
  EXPECT_EQ(p->value, 1);
  EXPECT_FALSE(q.pop());  // closed and empty: returns instead of blocking
}

TEST(BoundedQueue, ClearCountsDiscardedItemsAsDropped) {
  BoundedQueue<int> q(4, DropPolicy::DropOldest);
  q.push(1);
  q.push(2);
  EXPECT_EQ(q.clear(), 2u);
  EXPECT_EQ(q.droppedCount(), 2u);
  EXPECT_EQ(q.size(), 0u);
}

// A waiter for an empty queue (the daemon's source loop) wakes when the consumer takes the
// last item, and is refused once the queue is closed.
TEST(BoundedQueue, WaitUntilEmptyWakesWhenTheLastItemIsTaken) {
  BoundedQueue<int> q(2, DropPolicy::DropOldest);
  EXPECT_TRUE(q.waitUntilEmpty(std::chrono::milliseconds(0)));
  q.push(1);
  EXPECT_FALSE(q.waitUntilEmpty(std::chrono::milliseconds(20)));
  std::thread consumer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    q.pop();
  });
  EXPECT_TRUE(q.waitUntilEmpty(std::chrono::seconds(60)));
  consumer.join();
  q.close();
  EXPECT_FALSE(q.waitUntilEmpty(std::chrono::milliseconds(0)));
}

// No policy makes push wait: a producer (a stage's worker handing its result on) is never
// stalled by a consumer that does not pop.
TEST(BoundedQueue, PushNeverWaitsForAConsumer) {
  {
    BoundedQueue<int> q(1, DropPolicy::DropOldest);
    std::atomic<int> pushed{0};
    std::thread producer([&] {
      for (int i = 0; i < 100; ++i) {
        q.push(i);
        ++pushed;
      }
    });
    producer.join();  // would hang here if a push waited for room
    EXPECT_EQ(pushed.load(), 100);
    EXPECT_EQ(q.size(), 1u);
    EXPECT_EQ(q.droppedCount(), 99u);
  }
}

TEST(BoundedQueue, ZeroCapacityIsRejected) {
  EXPECT_THROW(BoundedQueue<int>(0, DropPolicy::DropOldest), std::invalid_argument);
}

TEST(ReorderBuffer, ReleasesInTicketOrderAndSkipsTombstones) {
  ReorderBuffer<int> r;
  r.insert(2, 20);
  EXPECT_TRUE(r.release().empty());  // 0 and 1 still missing
  r.insert(1, std::nullopt);         // ticket 1 failed
  EXPECT_TRUE(r.release().empty());
  r.insert(0, 0);
  EXPECT_EQ(r.release(), (std::vector<int>{0, 20}));
  EXPECT_EQ(r.nextTicket(), 3u);
  EXPECT_THROW(r.insert(1, 5), std::logic_error);  // already delivered
}

TEST(Stage, SequentialRunsInlineAndInOrder) {
  std::vector<int> out;
  std::vector<std::string> errors;
  Stage<int, int> stage({"double", ExecutionMode::Sequential, 1, 2},
                        {.work = [](int& x) -> std::optional<int> {
                           if (x == 3) throw Error("three is bad");
                           if (x == 4) return std::nullopt;
                           return 2 * x;
                         },
                         .emit = [&](int&& y) { out.push_back(y); },
                         .on_error = [&](const std::string& e) { errors.push_back(e); }});
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(stage.push(i));
  // No threads: results are there as soon as push returns.
  EXPECT_EQ(out, (std::vector<int>{0, 2, 4, 10}));
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("double: three is bad"), std::string::npos);
  const StageStats s = stage.stats();
  EXPECT_EQ(s.completed, 4u);
  EXPECT_EQ(s.failed, 2u);
  EXPECT_EQ(s.dropped, 0u);
  EXPECT_EQ(s.latency.samples, 6u);
  stage.stop(StopMode::Drain);
  EXPECT_FALSE(stage.push(7));
}

TEST(Stage, ParallelWorkersPublishInInputOrder) {
  // Random per-item work so that workers finish out of order; a queue as large as the input
  // makes sure nothing is dropped and every item must come out.
  constexpr int kItems = 200;
  std::mutex m;
  std::vector<int> out;
  std::atomic<int> concurrent{0}, max_concurrent{0};
  Stage<int, int> stage({"work", ExecutionMode::Threaded, 4, kItems, DropPolicy::DropOldest},
                        {.work = [&](int& x) -> std::optional<int> {
                           const int now = ++concurrent;
                           int seen = max_concurrent.load();
                           while (now > seen && !max_concurrent.compare_exchange_weak(seen, now)) {
                           }
                           std::mt19937 rng(static_cast<unsigned>(x));
                           std::this_thread::sleep_for(std::chrono::microseconds(rng() % 2000));
                           --concurrent;
                           if (x % 17 == 5) return std::nullopt;  // some items yield nothing
                           return x;
                         },
                         .emit =
                             [&](int&& y) {
                               std::lock_guard lock(m);
                               out.push_back(y);
                             }});
  stage.start();
  for (int i = 0; i < kItems; ++i) ASSERT_TRUE(stage.push(i));
  stage.stop(StopMode::Drain);
  std::vector<int> expected;
  for (int i = 0; i < kItems; ++i) {
    if (i % 17 != 5) expected.push_back(i);
  }
  EXPECT_EQ(out, expected);
  EXPECT_GT(max_concurrent.load(), 1) << "the workers never overlapped";
  EXPECT_EQ(stage.stats().in_flight, 0u);
}

TEST(Stage, SlowWorkerMakesTheQueueDropTheOldestItems) {
  // The worker is held on item 0 until all items have been offered, so the
  // queue (capacity 2) must keep only the two newest.
  std::mutex m;
  std::condition_variable cv;
  bool entered = false, release = false;
  std::vector<int> out;
  std::vector<int> dropped;
  Stage<int, int> stage({"slow", ExecutionMode::Threaded, 1, 2, DropPolicy::DropOldest},
                        {.work = [&](int& x) -> std::optional<int> {
                           std::unique_lock lock(m);
                           entered = true;
                           cv.notify_all();
                           cv.wait(lock, [&] { return release; });
                           return x;
                         },
                         .emit = [&](int&& y) { out.push_back(y); },
                         .on_drop = [&](const int& d) { dropped.push_back(d); }});
  stage.start();
  stage.push(0);
  {
    std::unique_lock lock(m);
    cv.wait(lock, [&] { return entered; });
  }
  for (int i = 1; i < 10; ++i) stage.push(i);
  EXPECT_EQ(stage.stats().queue_depth, 2u);
  EXPECT_EQ(stage.stats().in_flight, 1u);
  {
    std::lock_guard lock(m);
    release = true;
  }
  cv.notify_all();
  stage.stop(StopMode::Drain);
  EXPECT_EQ(out, (std::vector<int>{0, 8, 9}));
  EXPECT_EQ(dropped, (std::vector<int>{1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(stage.stats().dropped, 7u);
}

// The drop callback may take an evicted item's buffers (the daemon hands a dropped
// result's back to the Segmenter): it gets the item itself, not a copy.
TEST(Stage, AnEvictedItemIsTheDropCallbacksToMoveFrom) {
  std::mutex m;
  std::condition_variable cv;
  bool entered = false, release = false;
  std::vector<std::vector<int>> taken;
  Stage<std::vector<int>, int> stage(
      {"slow", ExecutionMode::Threaded, 1, 1, DropPolicy::DropOldest},
      {.work = [&](std::vector<int>& x) -> std::optional<int> {
         std::unique_lock lock(m);
         entered = true;
         cv.notify_all();
         cv.wait(lock, [&] { return release; });
         return static_cast<int>(x.size());
       },
       .emit = [](int&&) {},
       .on_drop = [&](std::vector<int>& d) { taken.push_back(std::move(d)); }});
  stage.start();
  stage.push({0});
  {
    std::unique_lock lock(m);
    cv.wait(lock, [&] { return entered; });
  }
  std::vector<int> big(1000, 7);
  const int* buffer = big.data();
  stage.push(std::move(big));
  stage.push({1, 2});  // evicts `big`
  ASSERT_EQ(taken.size(), 1u);
  EXPECT_EQ(taken[0].size(), 1000u);
  EXPECT_EQ(taken[0].data(), buffer);  // the same allocation, moved, not copied
  {
    std::lock_guard lock(m);
    release = true;
  }
  cv.notify_all();
  stage.stop(StopMode::Drain);
}

TEST(Stage, DiscardOnStopDropsQueuedItemsButFinishesTheOneInFlight) {
  std::mutex m;
  std::condition_variable cv;
  bool entered = false, release = false;
  std::vector<int> out;
  Stage<int, int> stage({"slow", ExecutionMode::Threaded, 1, 4, DropPolicy::DropOldest},
                        {.work = [&](int& x) -> std::optional<int> {
                           std::unique_lock lock(m);
                           entered = true;
                           cv.notify_all();
                           cv.wait(lock, [&] { return release; });
                           return x;
                         },
                         .emit = [&](int&& y) { out.push_back(y); }});
  stage.start();
  stage.push(0);
  {
    std::unique_lock lock(m);
    cv.wait(lock, [&] { return entered; });
  }
  stage.push(1);
  stage.push(2);
  std::thread stopper([&] { stage.stop(StopMode::Discard); });
  // stop() clears the queue before joining; wait for that, then let item 0 finish.
  while (stage.stats().queue_depth != 0) std::this_thread::yield();
  {
    std::lock_guard lock(m);
    release = true;
  }
  cv.notify_all();
  stopper.join();
  EXPECT_EQ(out, (std::vector<int>{0}));
  EXPECT_EQ(stage.stats().dropped, 2u);
}

TEST(Stage, TickRunsOnTheWorkerThread) {
  std::atomic<int> ticks{0};
  std::thread::id worker_id, tick_id;
  std::mutex m;
  Stage<int, int> stage({"tick", ExecutionMode::Threaded, 1, 2, DropPolicy::DropOldest, 10s, 1ms},
                        {.work = [&](int& x) -> std::optional<int> {
                           std::lock_guard lock(m);
                           worker_id = std::this_thread::get_id();
                           return x;
                         },
                         .emit = [](int&&) {},
                         .tick =
                             [&] {
                               std::lock_guard lock(m);
                               tick_id = std::this_thread::get_id();
                               ++ticks;
                             }});
  stage.start();
  stage.push(1);
  while (ticks.load() < 3) std::this_thread::sleep_for(1ms);
  stage.stop(StopMode::Drain);
  std::lock_guard lock(m);
  EXPECT_EQ(worker_id, tick_id);
  EXPECT_THROW((Stage<int, int>({"bad", ExecutionMode::Threaded, 2, 2},
                                {.work = [](int& x) { return std::optional<int>(x); },
                                 .emit = [](int&&) {},
                                 .tick = [] {}})),
               std::invalid_argument);
  // A stage without work or emit is refused at construction, not at the first item.
  EXPECT_THROW((Stage<int, int>({"no emit", ExecutionMode::Threaded, 1, 2},
                                {.work = [](int& x) { return std::optional<int>(x); }})),
               std::invalid_argument);
}

TEST(LatencyWindow, NearestRankPercentilesOverTheWindow) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::time_point{} + 100s;
  LatencyWindow w(10s);
  EXPECT_EQ(w.summary(t0).samples, 0u);
  for (int i = 1; i <= 100; ++i) w.add(i, t0);
  LatencySummary s = w.summary(t0);
  EXPECT_EQ(s.samples, 100u);
  EXPECT_DOUBLE_EQ(s.p50_ms, 50);
  EXPECT_DOUBLE_EQ(s.p95_ms, 95);
  EXPECT_DOUBLE_EQ(s.max_ms, 100);
  // Ten seconds later a new sample is all that is left in the window.
  w.add(7, t0 + 11s);
  s = w.summary(t0 + 11s);
  EXPECT_EQ(s.samples, 1u);
  EXPECT_DOUBLE_EQ(s.max_ms, 7);
}

TEST(RateMeter, SteadyStreamAndDecayAfterItStops) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::time_point{} + 100s;
  RateMeter r(100, 10s);
  for (int i = 0; i <= 20; ++i) r.tick(t0 + i * 250ms);  // 4 Hz for 5 s
  EXPECT_NEAR(r.rate(t0 + 5s), 4.0, 1e-9);
  EXPECT_LT(r.rate(t0 + 9s), 3.0);   // stopped: decays
  EXPECT_EQ(r.rate(t0 + 30s), 0.0);  // beyond the horizon
}

TEST(WatchdogGate, PingsWhileFramesProgressOrThePipelineIsIdle) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::time_point{} + 100s;
  WatchdogGate gate(5s);
  ProgressSnapshot p;
  p.source_heartbeat = t0;
  EXPECT_TRUE(gate.healthy(p, t0));
  // Idle for a long time (nothing pending) with a live source: still healthy.
  p.source_heartbeat = t0 + 20s;
  EXPECT_TRUE(gate.healthy(p, t0 + 20s));
  // Frames pending and completing: healthy.
  p.frames_pending = 2;
  p.frames_completed = 1;
  EXPECT_TRUE(gate.healthy(p, t0 + 21s));
  // Frames pending but nothing completes for longer than the stall limit:
  // no ping, even though the source keeps delivering.
  p.source_heartbeat = t0 + 25s;
  EXPECT_TRUE(gate.healthy(p, t0 + 25s));
  p.source_heartbeat = t0 + 27s;
  EXPECT_FALSE(gate.healthy(p, t0 + 27s));
  EXPECT_NE(gate.reason().find("pending"), std::string::npos);
  // Progress resumes.
  p.frames_completed = 2;
  EXPECT_TRUE(gate.healthy(p, t0 + 28s));
  // A source thread that stopped coming round is unhealthy.
  p.frames_pending = 0;
  EXPECT_FALSE(gate.healthy(p, t0 + 40s));
  EXPECT_NE(gate.reason().find("source"), std::string::npos);
}

TEST(DaemonConfig, ValuesAreParsedOnceIntoTheirFieldsAndDumped) {
  const LoadedConfig loaded =
      parseDaemonConfig("daemon:\n  workers: 3\n  queue_capacity: 4\n", "test.yaml");
  // No resolve step: the typed struct holds the parsed values once the text is read.
  const DaemonConfig& d = loaded.daemon;
  EXPECT_EQ(d.workers, 3);
  EXPECT_EQ(d.effectiveWorkers(), 3);
  EXPECT_EQ(d.queue_capacity, 4);
  EXPECT_EQ(d.status_period_s, 1.0);
  EXPECT_EQ(d.source, "openni2");
  // The effective config dump shows the daemon section with every key.
  const std::string dump = dumpDaemonConfig(loaded);
  EXPECT_NE(dump.find("publish_confidence: true"), std::string::npos);
  EXPECT_NE(dump.find("  workers: 3\n"), std::string::npos);
  EXPECT_NE(dump.find("  status_period_s: 1\n"), std::string::npos);
}

TEST(DaemonConfig, CpuBudgetBoundsTheSegmentationWorkers) {
  auto resolve = [](const std::string& yaml) { return parseDaemonConfig(yaml, "test.yaml").daemon; };
  const DaemonConfig none = resolve("daemon:\n  workers: 6\n");
  EXPECT_FALSE(none.singleThreaded());
  EXPECT_EQ(none.effectiveWorkers(), 6);
  const DaemonConfig one = resolve("daemon:\n  workers: 6\n  max_cpu_cores: 1\n");
  EXPECT_TRUE(one.singleThreaded());
  EXPECT_EQ(one.effectiveWorkers(), 1);
  const DaemonConfig one_half = resolve("daemon:\n  max_cpu_cores: 1.5\n");
  EXPECT_TRUE(one_half.singleThreaded());
  const DaemonConfig four = resolve("daemon:\n  workers: 6\n  max_cpu_cores: 4\n");
  EXPECT_FALSE(four.singleThreaded());
  EXPECT_EQ(four.effectiveWorkers(), 3);  // prepare keeps the fourth core busy
  const DaemonConfig roomy = resolve("daemon:\n  workers: 2\n  max_cpu_cores: 8\n");
  EXPECT_EQ(roomy.effectiveWorkers(), 2);  // the budget only ever lowers the count
  try {
    resolve("daemon:\n  max_cpu_cores: -1\n");
    ADD_FAILURE() << "a negative budget was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("daemon.max_cpu_cores"), std::string::npos) << e.what();
  }
}

TEST(DaemonConfig, HeapKeepIsReadAndBounded) {
  auto resolve = [](const std::string& yaml) { return parseDaemonConfig(yaml, "test.yaml").daemon; };
  EXPECT_EQ(resolve("daemon:\n  workers: 1\n").heap_keep_mb, 256);
  EXPECT_EQ(resolve("daemon:\n  heap_keep_mb: 0\n").heap_keep_mb, 0);
  EXPECT_EQ(resolve("daemon:\n  heap_keep_mb: 2047\n").heap_keep_mb, 2047);
  // 2048 MB would overflow mallopt's int byte count.
  for (const char* bad : {"-1", "2048", "lots"}) {
    try {
      resolve(std::string("daemon:\n  heap_keep_mb: ") + bad + "\n");
      ADD_FAILURE() << "heap_keep_mb " << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("daemon.heap_keep_mb"), std::string::npos) << e.what();
    }
  }
}

TEST(DaemonConfig, BadValuesAndUnknownKeysNameTheKey) {
  auto error_of = [](const std::string& yaml) -> std::string {
    try {
      parseDaemonConfig(yaml, "test.yaml");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of("daemon:\n  workers: -1\n").find("daemon.workers"), std::string::npos);
  EXPECT_NE(error_of("daemon:\n  queue_capacity: 0\n").find("daemon.queue_capacity"),
            std::string::npos);
  EXPECT_NE(error_of("daemon:\n  status_period_s: fast\n").find("daemon.status_period_s"),
            std::string::npos);
  EXPECT_NE(error_of("daemon:\n  publish_tables: maybe\n").find("daemon.publish_tables"),
            std::string::npos);
  EXPECT_NE(error_of("daemon:\n  channel_suffix: a-b\n").find("daemon.channel_suffix"),
            std::string::npos);
  EXPECT_NE(error_of("daemon:\n  lcm_url: nowhere\n").find("daemon.lcm_url"), std::string::npos);
  EXPECT_NE(error_of("daemon:\n  wokers: 2\n").find("test.yaml: line 2: unknown setting "
                                                     "'daemon.wokers' (daemon keys: "),
            std::string::npos)
      << error_of("daemon:\n  wokers: 2\n");
  // A section no program has (the old, never used `clients:`) is refused, named.
  EXPECT_NE(error_of("daemon:\n  workers: 2\nclients:\n  viewer_scale: 2\n")
                .find("unknown setting 'clients.viewer_scale': no section 'clients'"),
            std::string::npos);
  // findmug-web's section in a shared file: accepted, and its keys checked too.
  EXPECT_EQ(error_of("web:\n  port: 9000\n"), "");
  EXPECT_NE(error_of("web:\n  prot: 9000\n").find("web.prot"), std::string::npos);
}

TEST(DaemonConfig, CommandLineShortcutsBecomeOverrides) {
  const CommandLine cl = parseCommandLine(
      {"--config", "/x.yaml", "--workers", "2", "--set", "mrf.lambda=2", "--check-config"});
  EXPECT_EQ(cl.config_path, "/x.yaml");
  EXPECT_EQ(cl.overrides, (std::vector<std::string>{"daemon.workers=2", "mrf.lambda=2"}));
  EXPECT_TRUE(cl.check_config);
  EXPECT_THROW(parseCommandLine({"--frobnicate"}), Error);
  EXPECT_THROW(parseCommandLine({"--config"}), Error);
}

TEST(DaemonConfig, LcmDefaultUrlIsUsedWhenTheConfigLeavesItEmpty) {
  DaemonConfig d;
  setenv("LCM_DEFAULT_URL", "memq://", 1);
  EXPECT_EQ(effectiveLcmUrl(d), "memq://");
  d.lcm_url = "file:///tmp/x.lcmlog?mode=w";
  EXPECT_EQ(effectiveLcmUrl(d), "file:///tmp/x.lcmlog?mode=w");
  unsetenv("LCM_DEFAULT_URL");
}

}  // namespace
}  // namespace findmug::daemon

namespace findmug::daemon {
namespace {

// The offline tools' sections of a config file (training, degrade, table_metrics) as
// findmug-train and findmug-eval read them; the daemon only accepts them, so its
// dump leaves them out. Built-in defaults when `path` is empty.
std::string offlineSectionsDump(const std::string& path) {
  Config config;
  SettingsSchema core_and_offline;
  bindCoreSettings(core_and_offline, config);
  bindOfflineSettings(core_and_offline, config);
  cli::acceptSharedFileSettings(core_and_offline);
  if (!path.empty()) core_and_offline.readFile(path);
  core_and_offline.validate(path.empty() ? "<built-in>" : path);
  SettingsSchema offline_only;
  offline_only.bind(offlineSettings(), config.offline);
  return offline_only.dump();
}

// Every key of the file as the programs that bind it read it: the daemon's
// dump (core, daemon, maps, check) and the offline tools' sections.
std::string wholeFileDump(const std::string& path) {
  CommandLine command_line;
  if (!path.empty()) command_line.config_path = path;
  const LoadedConfig loaded =
      path.empty() ? parseDaemonConfig("", "<built-in>") : loadDaemonConfig(command_line);
  return dumpDaemonConfig(loaded) + offlineSectionsDump(path);
}

// The shipped default config must load, and must document every key the
// programs know (core, offline and daemon): a key added to config.hpp,
// offline_settings.hpp or daemon_config.hpp without a line in
// daemon/findmugd.yaml fails here.
TEST(DaemonConfig, ShippedDefaultFileIsValidAndDocumentsEveryKey) {
  const std::string path = (findmug::test::sourceDir() / "daemon" / "findmugd.yaml").string();
  CommandLine command_line;
  command_line.config_path = path;
  const LoadedConfig loaded = loadDaemonConfig(command_line);
  EXPECT_EQ(loaded.daemon.source, "openni2");
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  const std::string whole = wholeFileDump(path);
  for (const char* section : {"training:", "degrade:", "table_metrics:"})
    EXPECT_NE(whole.find(std::string("\n") + section + "\n"), std::string::npos) << section;
  std::istringstream dump(whole);
  std::string line, section;
  int keys = 0;
  while (std::getline(dump, line)) {
    if (line.empty()) continue;
    if (line[0] != ' ') {
      section = line.substr(0, line.find(':'));
      EXPECT_NE(text.find("\n" + section + ":\n"), std::string::npos) << "section " << section;
      continue;
    }
    const std::string key = line.substr(2, line.find(':') - 2);
    ++keys;
    // Set, or shown commented out with its default.
    const bool documented = text.find("\n  " + key + ":") != std::string::npos ||
                            text.find("\n  # " + key + ":") != std::string::npos;
    EXPECT_TRUE(documented) << section << "." << key << " is not in " << path;
  }
  EXPECT_GT(keys, 40);
}

// The effective values of a config dump, "section.key" -> "value".
std::map<std::string, std::string> flattenDump(const std::string& dump) {
  std::map<std::string, std::string> values;
  std::istringstream in(dump);
  std::string line, section;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const auto colon = line.find(':');
    if (line[0] != ' ') {
      section = line.substr(0, colon);
      continue;
    }
    const std::string key = line.substr(2, colon - 2);
    std::string value = colon + 1 < line.size() ? line.substr(colon + 1) : "";
    if (!value.empty() && value[0] == ' ') value.erase(0, 1);
    values[section + "." + key] = value;
  }
  return values;
}

// The comment block above `key:` in `section:` of the YAML text, and the key's own line.
std::string commentsOfKey(const std::string& text, const std::string& section,
                          const std::string& key) {
  const auto section_at = text.find("\n" + section + ":\n");
  if (section_at == std::string::npos) return {};
  const auto key_at = text.find("\n  " + key + ":", section_at);
  if (key_at == std::string::npos) return {};
  auto line_end = text.find('\n', key_at + 1);
  std::string block = text.substr(key_at + 1, line_end - key_at - 1);
  std::size_t end = key_at;  // walk back over the comment lines right above the key
  while (end > 0) {
    const auto start = text.rfind('\n', end - 1);
    const std::string above = text.substr(start + 1, end - start - 1);
    if (above.rfind("  #", 0) != 0) break;
    block = above + "\n" + block;
    end = start;
  }
  return block;
}

// Both directions between daemon/findmugd.yaml and the built-in defaults: the file
// names the same keys as the built-in configuration, and every value it sets is
// the built-in default unless the comment on that key says "not the built-in
// default" and why, so that a reader of the file never mistakes a choice for a default.
TEST(DaemonConfig, ShippedFileHoldsTheBuiltInDefaultsOrSaysWhyNot) {
  const std::string path = (findmug::test::sourceDir() / "daemon" / "findmugd.yaml").string();
  const auto file_values = flattenDump(wholeFileDump(path));
  const auto default_values = flattenDump(wholeFileDump(""));
  EXPECT_TRUE(default_values.count("training.degraded_seed"));  // the offline sections too
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  int differing = 0;
  for (const auto& [key, value] : default_values) {
    const auto it = file_values.find(key);
    ASSERT_NE(it, file_values.end()) << key << " is a built-in key the shipped file lacks";
    if (it->second == value) continue;
    ++differing;
    const auto dot = key.find('.');
    const std::string comments = commentsOfKey(text, key.substr(0, dot), key.substr(dot + 1));
    EXPECT_NE(comments.find("not the built-in default"), std::string::npos)
        << key << " is " << it->second << " in " << path << " but " << value
        << " built in, and its comment does not say 'not the built-in default' and why";
  }
  for (const auto& [key, value] : file_values) {
    EXPECT_TRUE(default_values.count(key)) << key << " in the shipped file is no built-in key";
  }
  // The file is read as a whole: a lost section or key would show as a smaller count.
  EXPECT_GT(default_values.size(), 40u);
  EXPECT_LT(differing, static_cast<int>(default_values.size()) / 4);
}

}  // namespace
}  // namespace findmug::daemon

namespace findmug::daemon {
namespace {

// Journal logging is chosen only when JOURNAL_STREAM names stderr itself
// (systemd's documented check), not merely because the variable is set.
TEST(Logging, JournalIsDetectedOnlyWhenJournalStreamMatchesStderr) {
  struct stat st {};
  ASSERT_EQ(fstat(STDERR_FILENO, &st), 0);
  const std::string own = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
  setenv("JOURNAL_STREAM", own.c_str(), 1);
  EXPECT_TRUE(stderrIsJournal());
  setenv("JOURNAL_STREAM",
         (std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino + 1)).c_str(), 1);
  EXPECT_FALSE(stderrIsJournal());
  setenv("JOURNAL_STREAM", "garbage", 1);
  EXPECT_FALSE(stderrIsJournal());
  unsetenv("JOURNAL_STREAM");
  EXPECT_FALSE(stderrIsJournal());
}

}  // namespace
}  // namespace findmug::daemon
