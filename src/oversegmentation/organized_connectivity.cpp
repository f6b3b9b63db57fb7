// organized_connectivity.cpp — the organized oversegmenter's step 5 (see
// oversegmentation_organized.cpp): every label split into its 4-connected pieces, small
// pieces merged into the neighbour they share the longest border with. Works on
// horizontal runs of equal key (a few tens per row) rather than on pixels.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

#include "common/int_runs.hpp"
#include "common/scratch.hpp"
#include "oversegmentation/organized_internal.hpp"

namespace findmug::detail::organized {
namespace {

struct Run {  // enforceConnectivity: [x0, x1) of one row with one key
  int x0, x1;
  int key;
};
struct Contact {       // enforceConnectivity: border between a small piece and a neighbour
  std::uint64_t pair;  // small << 32 | neighbour
  int length;
};
// enforceConnectivity's working memory, kept per thread between frames (scratch.hpp).
struct ConnectivityBuffers {
  std::vector<std::uint8_t> small;
  std::vector<Run> runs;
  std::vector<int> row_begin, parent, run_piece, piece_size, piece_key, merged, target, target_len;
  std::vector<Contact> contacts;
};
thread_local ConnectivityBuffers g_connectivity_buffers;

using detail::Borrowed;

// enforceConnectivity's steps. The runs of row y are runs[row_begin[y] ..
// row_begin[y + 1]).

// The horizontal runs of equal key, row by row; unusable pixels (key -1)
// are in none.
void findKeyRuns(int w, int h, const std::vector<int>& key, std::vector<Run>& runs,
                 std::vector<int>& row_begin) {
  runs.clear();
  row_begin.assign(static_cast<std::size_t>(h) + 1, 0);
  for (int y = 0; y < h; ++y) {
    row_begin[y] = static_cast<int>(runs.size());
    const int* row = key.data() + static_cast<std::size_t>(y) * w;
    for (int x = 0; x < w;) {
      const int k = row[x];
      const int x1 = static_cast<int>(
          detail::intRunEnd(row, static_cast<std::size_t>(x), static_cast<std::size_t>(w)));
      if (k != -1) runs.push_back({x, x1, k});
      x = x1;
    }
  }
  row_begin[h] = static_cast<int>(runs.size());
}

// Calls f(upper run, lower run, overlap) for vertically touching runs.
template <typename F>
void forEachVerticalContact(int h, const std::vector<Run>& runs, const std::vector<int>& row_begin,
                            F&& f) {
  for (int y = 1; y < h; ++y) {
    int a = row_begin[y - 1];
    int b = row_begin[y];
    while (a < row_begin[y] && b < row_begin[y + 1]) {
      const int overlap = std::min(runs[a].x1, runs[b].x1) - std::max(runs[a].x0, runs[b].x0);
      if (overlap > 0) f(a, b, overlap);
      if (runs[a].x1 < runs[b].x1) {
        ++a;
      } else {
        ++b;
      }
    }
  }
}

// Pieces: the 4-connected groups of runs of one key (union-find over
// vertically touching runs), dense ids in the order of their first run
// (`run_piece` per run), with their sizes in pixels and their keys.
void findPieces(int h, const std::vector<Run>& runs, const std::vector<int>& row_begin,
                std::vector<int>& run_piece, std::vector<int>& piece_size,
                std::vector<int>& piece_key) {
  const int run_count = static_cast<int>(runs.size());
  Borrowed parent_buffer(g_connectivity_buffers.parent);
  std::vector<int>& parent = *parent_buffer;
  parent.resize(run_count);
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&parent](int p) {
    while (parent[p] != p) {
      parent[p] = parent[parent[p]];
      p = parent[p];
    }
    return p;
  };
  const auto unite = [&](int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  forEachVerticalContact(h, runs, row_begin, [&](int a, int b, int) {
    if (runs[a].key == runs[b].key) unite(a, b);
  });

  run_piece.resize(run_count);
  piece_size.clear();
  piece_key.clear();
  for (int r = 0; r < run_count; ++r) {
    const int root = find(r);
    if (root == r) {
      run_piece[r] = static_cast<int>(piece_size.size());
      piece_size.push_back(0);
      piece_key.push_back(runs[r].key);
    } else {
      run_piece[r] = run_piece[root];  // roots precede their runs
    }
    piece_size[run_piece[r]] += runs[r].x1 - runs[r].x0;
  }
}

// small[p]: piece p is below oversegmentation.min_segment_points or a quarter of
// its cluster's nominal area, or no cluster reached it. Returns whether
// any piece is small.
bool markSmallPieces(const std::vector<Cluster>& clusters, const std::vector<int>& piece_size,
                     const std::vector<int>& piece_key, int min_segment_points,
                     std::vector<std::uint8_t>& small) {
  const int pieces = static_cast<int>(piece_size.size());
  small.assign(pieces, 0);
  bool any_small = false;
  for (int p = 0; p < pieces; ++p) {
    const float nominal = piece_key[p] >= 0 ? clusters[piece_key[p]].nominal_area_px : 0.0f;
    const float threshold = std::max(static_cast<float>(min_segment_points), 0.25f * nominal);
    small[p] = piece_size[p] < threshold || piece_key[p] == kUnassigned;
    any_small = any_small || small[p];
  }
  return any_small;
}

// merged[p] (every piece its own on entry): the piece that small piece p
// joins, the neighbour it shares the longest border with, followed
// through chains.
void mergeSmallPieces(int h, const std::vector<Run>& runs, const std::vector<int>& row_begin,
                      const std::vector<int>& run_piece, const std::vector<std::uint8_t>& small,
                      std::vector<int>& merged) {
  const int pieces = static_cast<int>(small.size());
  // Border lengths between a small piece and its neighbours.
  Borrowed contacts_buffer(g_connectivity_buffers.contacts);
  std::vector<Contact>& contacts = *contacts_buffer;
  contacts.clear();
  const auto touch = [&](int pa, int pb, int length) {
    if (pa == pb) return;
    if (small[pa])
      contacts.push_back(
          {(static_cast<std::uint64_t>(pa) << 32) | static_cast<std::uint32_t>(pb), length});
    if (small[pb])
      contacts.push_back(
          {(static_cast<std::uint64_t>(pb) << 32) | static_cast<std::uint32_t>(pa), length});
  };
  for (int y = 0; y < h; ++y) {
    for (int r = row_begin[y]; r + 1 < row_begin[y + 1]; ++r) {
      if (runs[r].x1 == runs[r + 1].x0) touch(run_piece[r], run_piece[r + 1], 1);
    }
  }
  forEachVerticalContact(h, runs, row_begin, [&](int a, int b, int overlap) {
    touch(run_piece[a], run_piece[b], overlap);
  });
  std::sort(contacts.begin(), contacts.end(),
            [](const Contact& a, const Contact& b) { return a.pair < b.pair; });
  Borrowed target_buffer(g_connectivity_buffers.target);
  std::vector<int>& target = *target_buffer;  // neighbour with the longest border
  target.assign(pieces, -1);
  Borrowed target_len_buffer(g_connectivity_buffers.target_len);
  std::vector<int>& target_len = *target_len_buffer;
  target_len.assign(pieces, 0);
  for (std::size_t i = 0; i < contacts.size();) {
    int length = 0;
    std::size_t j = i;
    for (; j < contacts.size() && contacts[j].pair == contacts[i].pair; ++j)
      length += contacts[j].length;
    const int a = static_cast<int>(contacts[i].pair >> 32);
    if (length > target_len[a]) {
      target_len[a] = length;
      target[a] = static_cast<int>(contacts[i].pair & 0xffffffffu);
    }
    i = j;
  }
  // Union-find resolves chains (a small piece into a small piece into a
  // big one) and pairs of small pieces that chose each other.
  const auto find_merged = [&merged](int p) {
    while (merged[p] != p) {
      merged[p] = merged[merged[p]];
      p = merged[p];
    }
    return p;
  };
  for (int p = 0; p < pieces; ++p) {
    if (!small[p] || target[p] < 0) continue;
    const int a = find_merged(p);
    const int b = find_merged(target[p]);
    if (a != b) merged[a] = b;
  }
  for (int p = 0; p < pieces; ++p) merged[p] = find_merged(p);
}

// Each pixel once: the runs their pieces' merged ids, the gaps between
// them -1.
void writePieceIds(int w, int h, const std::vector<Run>& runs, const std::vector<int>& row_begin,
                   const std::vector<int>& run_piece, const std::vector<int>& merged,
                   std::vector<int>& out) {
  for (int y = 0; y < h; ++y) {
    int* row = out.data() + static_cast<std::size_t>(y) * w;
    int x = 0;
    for (int r = row_begin[y]; r < row_begin[y + 1]; ++r) {
      std::fill(row + x, row + runs[r].x0, -1);
      std::fill(row + runs[r].x0, row + runs[r].x1, merged[run_piece[r]]);
      x = runs[r].x1;
    }
    std::fill(row + x, row + w, -1);
  }
}

}  // namespace

void enforceConnectivity(int w, int h, const std::vector<Cluster>& clusters,
                         const std::vector<int>& key, int min_segment_points,
                         std::vector<int>& out) {
  Borrowed runs_buffer(g_connectivity_buffers.runs);
  std::vector<Run>& runs = *runs_buffer;
  Borrowed row_begin_buffer(g_connectivity_buffers.row_begin);
  std::vector<int>& row_begin = *row_begin_buffer;
  findKeyRuns(w, h, key, runs, row_begin);

  Borrowed run_piece_buffer(g_connectivity_buffers.run_piece);
  std::vector<int>& run_piece = *run_piece_buffer;
  Borrowed piece_size_buffer(g_connectivity_buffers.piece_size);
  std::vector<int>& piece_size = *piece_size_buffer;
  Borrowed piece_key_buffer(g_connectivity_buffers.piece_key);
  std::vector<int>& piece_key = *piece_key_buffer;
  findPieces(h, runs, row_begin, run_piece, piece_size, piece_key);

  const int pieces = static_cast<int>(piece_size.size());
  Borrowed small_buffer(g_connectivity_buffers.small);
  std::vector<std::uint8_t>& small = *small_buffer;
  const bool any_small =
      markSmallPieces(clusters, piece_size, piece_key, min_segment_points, small);

  Borrowed merged_buffer(g_connectivity_buffers.merged);
  std::vector<int>& merged = *merged_buffer;
  merged.resize(pieces);
  std::iota(merged.begin(), merged.end(), 0);
  if (any_small) mergeSmallPieces(h, runs, row_begin, run_piece, small, merged);
  writePieceIds(w, h, runs, row_begin, run_piece, merged, out);
}

}  // namespace findmug::detail::organized
