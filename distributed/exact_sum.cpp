#include "exact_sum.h"

#include <limits>
#include <vector>

namespace snow::dist {

double exactSum(const Communicator& comm, const Decomposition& d, const float* values, const uint8_t* valid) {
  const int self = comm.rank(), column = d.columnOf(self), row = d.rowOf(self);
  const CellRect mine = d.owned(self), at = d.local(self);
  std::vector<double> rows(static_cast<size_t>(mine.height()), 0.0);
  if (column > 0) comm.exchange({}, {{d.rankAt(column - 1, row), rows.data(), rows.size() * sizeof(double)}});
  for (int y = mine.y0; y < mine.y1; ++y) {
    double s = rows[y - mine.y0];
    const size_t first = at.offsetOf(mine.x0, y);
    for (size_t i = first; i < first + static_cast<size_t>(mine.width()); ++i)
      if (valid[i]) s += static_cast<double>(values[i]);
    rows[y - mine.y0] = s;
  }
  const bool last = column == d.columns - 1;
  if (!last) comm.exchange({{d.rankAt(column + 1, row), rows.data(), rows.size() * sizeof(double)}}, {});
  // Ranks are numbered row-major: the last column's rows come in the grid's row order.
  const std::vector<double> all = comm.allGather(last ? rows : std::vector<double>());
  double total = 0.0;
  for (double r : all) total += r;
  return total;
}

float exactMax(const Communicator& comm, const Decomposition& d, const float* values, const uint8_t* valid) {
  const CellRect mine = d.owned(comm.rank()), at = d.local(comm.rank());
  float m = -std::numeric_limits<float>::infinity();
  for (int y = mine.y0; y < mine.y1; ++y) {
    const size_t first = at.offsetOf(mine.x0, y);
    for (size_t i = first; i < first + static_cast<size_t>(mine.width()); ++i)
      if (valid[i] && values[i] > m) m = values[i];
  }
  return comm.maxOverRanks(m);
}

}  // namespace snow::dist
