// The process helpers of the findmug programs (cli/): StopSignals (SIGINT /
// SIGTERM -> a stop flag and stop actions) and the JSON writer.
#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "findmug_json.hpp"
#include "findmug_signals.hpp"

namespace findmug::cli {
namespace {

using namespace std::chrono_literals;

// A process-directed signal, as `kill` or systemd send it. (raise() would aim at
// the calling thread, which StopSignals has blocked the signal in.)
void signalProcess(int signal_number) { ASSERT_EQ(kill(getpid(), signal_number), 0); }

bool blockedHere(int signal_number) {
  sigset_t mask;
  pthread_sigmask(SIG_BLOCK, nullptr, &mask);
  return sigismember(&mask, signal_number) == 1;
}

TEST(StopSignals, SigtermSetsTheFlagAndRunsTheActionOnce) {
  StopSignals signals;
  EXPECT_FALSE(signals.requested());
  EXPECT_EQ(signals.signalNumber(), 0);
  std::atomic<int> runs{0};
  const auto registration = signals.onStop([&runs] { ++runs; });
  signalProcess(SIGTERM);
  ASSERT_TRUE(signals.waitFor(60s));
  EXPECT_EQ(signals.signalNumber(), SIGTERM);
  // A second signal is taken by the same thread and changes nothing.
  signalProcess(SIGINT);
  while (runs.load() == 0) std::this_thread::sleep_for(1ms);
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(runs.load(), 1);
  EXPECT_EQ(signals.signalNumber(), SIGTERM);
}

TEST(StopSignals, SigintCountsToo) {
  StopSignals signals;
  signalProcess(SIGINT);
  ASSERT_TRUE(signals.waitFor(60s));
  EXPECT_EQ(signals.signalNumber(), SIGINT);
}

TEST(StopSignals, NoSignalNoStop) {
  StopSignals signals;
  EXPECT_FALSE(signals.waitFor(20ms));
  EXPECT_FALSE(signals.requested());
}

TEST(StopSignals, AnActionRegisteredAfterTheSignalRunsAtOnce) {
  StopSignals signals;
  signalProcess(SIGTERM);
  ASSERT_TRUE(signals.waitFor(60s));
  bool ran = false;
  const auto registration = signals.onStop([&ran] { ran = true; });
  EXPECT_TRUE(ran);
}

TEST(StopSignals, AnUnregisteredActionDoesNotRun) {
  StopSignals signals;
  std::atomic<int> kept{0}, dropped{0};
  const auto keep = signals.onStop([&kept] { ++kept; });
  {
    const auto drop = signals.onStop([&dropped] { ++dropped; });
  }
  signalProcess(SIGTERM);
  ASSERT_TRUE(signals.waitFor(60s));
  while (kept.load() == 0) std::this_thread::sleep_for(1ms);
  EXPECT_EQ(dropped.load(), 0);
}

TEST(StopSignals, BlocksTheSignalsWhileAliveAndRestoresTheMask) {
  ASSERT_FALSE(blockedHere(SIGTERM));
  {
    StopSignals signals;
    EXPECT_TRUE(blockedHere(SIGTERM));
    EXPECT_TRUE(blockedHere(SIGINT));
    // Threads started now inherit the mask: no EINTR for them.
    bool blocked_in_thread = false;
    std::thread([&] { blocked_in_thread = blockedHere(SIGINT); }).join();
    EXPECT_TRUE(blocked_in_thread);
  }
  EXPECT_FALSE(blockedHere(SIGTERM));
  EXPECT_FALSE(blockedHere(SIGINT));
}

TEST(StopSignals, ASignalTakenByAThreadStartedBeforeStillCounts) {
  std::atomic<bool> go{false};
  std::thread early([&go] {  // started before StopSignals: SIGINT not blocked here
    while (!go) std::this_thread::sleep_for(1ms);
    pthread_kill(pthread_self(), SIGINT);
  });
  StopSignals signals;
  go = true;
  early.join();
  ASSERT_TRUE(signals.waitFor(60s));
  EXPECT_EQ(signals.signalNumber(), SIGINT);
}

TEST(JsonWriter, StringsAreQuotedAndEscaped) {
  EXPECT_EQ(jsonString(""), "\"\"");
  EXPECT_EQ(jsonString("table 1"), "\"table 1\"");
  EXPECT_EQ(jsonString("say \"hi\""), "\"say \\\"hi\\\"\"");
  EXPECT_EQ(jsonString("C:\\path"), "\"C:\\\\path\"");
  EXPECT_EQ(jsonString("a\nb\tc"), "\"a\\nb\\tc\"");
}

TEST(JsonWriter, ControlCharactersBecomeUnicodeEscapes) {
  EXPECT_EQ(jsonString(std::string("\x01", 1)), "\"\\u0001\"");
  EXPECT_EQ(jsonString("\r"), "\"\\u000d\"");
  EXPECT_EQ(jsonString("\x1f"), "\"\\u001f\"");
  EXPECT_EQ(jsonString(std::string("a\0b", 3)), "\"a\\u0000b\"");
  EXPECT_EQ(jsonString("\x7f"), "\"\x7f\"");  // DEL is allowed as is
}

TEST(JsonWriter, Utf8PassesThrough) {
  EXPECT_EQ(jsonString("Küche – 台所 ☕"), "\"Küche – 台所 ☕\"");
}

TEST(JsonWriter, NumbersAreFixedPointAndNonFiniteIsNull) {
  EXPECT_EQ(jsonNumber(1.5, 3), "1.500");
  EXPECT_EQ(jsonNumber(-0.25, 2), "-0.25");
  EXPECT_EQ(jsonNumber(2.0 / 3.0, 6), "0.666667");
  EXPECT_EQ(jsonNumber(42.0, 0), "42");
  EXPECT_EQ(jsonNumber(std::numeric_limits<double>::quiet_NaN(), 3), "null");
  EXPECT_EQ(jsonNumber(std::numeric_limits<double>::infinity(), 3), "null");
  EXPECT_EQ(jsonNumber(-std::numeric_limits<double>::infinity(), 3), "null");
  // The largest double still fits.
  EXPECT_EQ(jsonNumber(std::numeric_limits<double>::max(), 1).size(), 309u + 2u);
}

}  // namespace
}  // namespace findmug::cli
