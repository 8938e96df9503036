#include "distributed_wave.hpp"

#include "mpi_support.hpp"

#include <mpi.h>

#include <fmt/format.h>

#include <algorithm>
#include <utility>

namespace stepwise {

namespace {

// part p of `parts` of n points: the first n % parts parts one longer
std::pair<int, int> share(int n, int parts, int p) {
  const int base = n / parts, extra = n % parts;
  return {p * base + std::min(p, extra), base + (p < extra ? 1 : 0)};
}

}  // namespace

struct DistributedWave::Impl {
  int rows = 0, cols = 0;  // the whole grid
  WaveCoefficients k;
  MPI_Comm cart = MPI_COMM_NULL;
  int dims[2] = {1, 1}, coords[2] = {0, 0};
  int up = MPI_PROC_NULL, down = MPI_PROC_NULL, left = MPI_PROC_NULL, right = MPI_PROC_NULL;
  Block block;
  int stride = 0;                          // block.cols + 2
  std::vector<double> z_prev, z;           // (block.rows + 2) x stride, the halo around the block
  MPI_Datatype column = MPI_DATATYPE_NULL;  // block.rows doubles a stride apart

  ~Impl() {
    if (column != MPI_DATATYPE_NULL) MPI_Type_free(&column);
    if (cart != MPI_COMM_NULL) MPI_Comm_free(&cart);
  }

  double* at(std::vector<double>& v, int a, int b) { return v.data() + static_cast<std::ptrdiff_t>(a) * stride + b; }

  // the cells of local rows [a0, a1) and columns [b0, b1) that are the grid's interior (the boundary holds still)
  void update(int a0, int a1, int b0, int b1) {
    // local row a is global row row0 + a - 1; the interior is global rows 1 .. rows - 2
    a0 = std::max(a0, 2 - block.row0);
    a1 = std::min(a1, rows - block.row0);
    b0 = std::max(b0, 2 - block.col0);
    b1 = std::min(b1, cols - block.col0);
    if (a0 >= a1 || b0 >= b1) return;
    wave_step_rows(k, stride, a1 - a0, b0, b1, at(z_prev, a0, 0), at(z, a0, 0));
  }

  // post the halo's receives and sends of z; the eight requests (null towards the grid's edges)
  void exchange(MPI_Request* requests) {
    const int r = block.rows, c = block.cols;
    double* zz = z.data();
    const auto cell = [&](int a, int b) { return zz + static_cast<std::ptrdiff_t>(a) * stride + b; };
    mpi_check(MPI_Irecv(cell(0, 1), c, MPI_DOUBLE, up, 0, cart, &requests[0]), "MPI_Irecv");
    mpi_check(MPI_Irecv(cell(r + 1, 1), c, MPI_DOUBLE, down, 1, cart, &requests[1]), "MPI_Irecv");
    mpi_check(MPI_Irecv(cell(1, 0), 1, column, left, 2, cart, &requests[2]), "MPI_Irecv");
    mpi_check(MPI_Irecv(cell(1, c + 1), 1, column, right, 3, cart, &requests[3]), "MPI_Irecv");
    mpi_check(MPI_Isend(cell(1, 1), c, MPI_DOUBLE, up, 1, cart, &requests[4]), "MPI_Isend");
    mpi_check(MPI_Isend(cell(r, 1), c, MPI_DOUBLE, down, 0, cart, &requests[5]), "MPI_Isend");
    mpi_check(MPI_Isend(cell(1, 1), 1, column, left, 3, cart, &requests[6]), "MPI_Isend");
    mpi_check(MPI_Isend(cell(1, c), 1, column, right, 2, cart, &requests[7]), "MPI_Isend");
  }
};

DistributedWave::DistributedWave(int rows, int cols, const WaveCoefficients& k, bool alone) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.rows = rows;
  m.cols = cols;
  m.k = k;
  int size = 1;
  const MPI_Comm world = alone ? MPI_COMM_SELF : MPI_COMM_WORLD;
  mpi_check(MPI_Comm_size(world, &size), "MPI_Comm_size");
  m.dims[0] = m.dims[1] = 0;  // both free
  mpi_check(MPI_Dims_create(size, 2, m.dims), "MPI_Dims_create");
  // the longer side gets the more ranks
  if ((rows < cols) != (m.dims[0] < m.dims[1])) std::swap(m.dims[0], m.dims[1]);
  if (m.dims[0] > rows || m.dims[1] > cols)
    throw DecompositionError(fmt::format("{} ranks make a {} x {} decomposition, more than the grid's {} rows or {} columns", size, m.dims[0],
                                         m.dims[1], rows, cols));
  const int periods[2] = {0, 0};
  mpi_check(MPI_Cart_create(world, 2, m.dims, periods, 0, &m.cart), "MPI_Cart_create");
  int rank = 0;
  mpi_check(MPI_Comm_rank(m.cart, &rank), "MPI_Comm_rank");
  mpi_check(MPI_Cart_coords(m.cart, rank, 2, m.coords), "MPI_Cart_coords");
  mpi_check(MPI_Cart_shift(m.cart, 0, 1, &m.up, &m.down), "MPI_Cart_shift");
  mpi_check(MPI_Cart_shift(m.cart, 1, 1, &m.left, &m.right), "MPI_Cart_shift");
  const auto [row0, nrows] = share(rows, m.dims[0], m.coords[0]);
  const auto [col0, ncols] = share(cols, m.dims[1], m.coords[1]);
  m.block = {row0, nrows, col0, ncols};
  m.stride = ncols + 2;
  m.z_prev.assign(static_cast<size_t>(nrows + 2) * static_cast<size_t>(m.stride), 0.0);
  m.z = m.z_prev;
  mpi_check(MPI_Type_vector(nrows, 1, m.stride, MPI_DOUBLE, &m.column), "MPI_Type_vector");
  mpi_check(MPI_Type_commit(&m.column), "MPI_Type_commit");
}

DistributedWave::~DistributedWave() = default;

std::array<int, 2> DistributedWave::dims() const { return {impl_->dims[0], impl_->dims[1]}; }
DistributedWave::Block DistributedWave::block() const { return impl_->block; }

DistributedWave::Halo DistributedWave::halo() const {
  const Impl& m = *impl_;
  Halo h;
  for (const auto& [neighbour, doubles] : {std::pair{m.up, m.block.cols}, {m.down, m.block.cols}, {m.left, m.block.rows}, {m.right, m.block.rows}})
    if (neighbour != MPI_PROC_NULL) {
      ++h.messages;
      h.bytes += 8L * doubles;
    }
  return h;
}

void DistributedWave::set(const double* z_prev, const double* z) {
  Impl& m = *impl_;
  for (int a = 0; a < m.block.rows; ++a)
    for (int b = 0; b < m.block.cols; ++b) {
      const std::ptrdiff_t global = static_cast<std::ptrdiff_t>(m.block.row0 + a) * m.cols + m.block.col0 + b;
      *m.at(m.z_prev, a + 1, b + 1) = z_prev[global];
      *m.at(m.z, a + 1, b + 1) = z[global];
    }
}

void DistributedWave::step(int steps, bool overlap) {
  Impl& m = *impl_;
  const int r = m.block.rows, c = m.block.cols;
  for (int s = 0; s < steps; ++s) {
    MPI_Request requests[8];
    m.exchange(requests);
    if (overlap) {
      m.update(2, r, 2, c);  // the cells whose four neighbours are the block's own
      mpi_check(MPI_Waitall(8, requests, MPI_STATUSES_IGNORE), "MPI_Waitall");
      // the edge ring: the first and last rows whole, the first and last columns between them
      m.update(1, 2, 1, c + 1);
      if (r > 1) m.update(r, r + 1, 1, c + 1);
      m.update(2, r, 1, 2);
      if (c > 1) m.update(2, r, c, c + 1);
    } else {
      mpi_check(MPI_Waitall(8, requests, MPI_STATUSES_IGNORE), "MPI_Waitall");
      m.update(1, r + 1, 1, c + 1);
    }
    std::swap(m.z_prev, m.z);  // z^{k+1} was written over z^{k-1}
  }
}

std::vector<double> DistributedWave::gather() const {
  const Impl& m = *impl_;
  std::vector<double> mine;
  mine.reserve(static_cast<size_t>(m.block.rows) * static_cast<size_t>(m.block.cols));
  for (int a = 1; a <= m.block.rows; ++a)
    for (int b = 1; b <= m.block.cols; ++b) mine.push_back(m.z[static_cast<size_t>(a) * static_cast<size_t>(m.stride) + static_cast<size_t>(b)]);
  return gather(mine);
}

double* DistributedWave::level() { return impl_->z.data(); }
int DistributedWave::stride() const { return impl_->stride; }

void DistributedWave::exchange() {
  MPI_Request requests[8];
  impl_->exchange(requests);
  mpi_check(MPI_Waitall(8, requests, MPI_STATUSES_IGNORE), "MPI_Waitall");
}

std::vector<double> DistributedWave::gather(const std::vector<double>& mine) const {
  const Impl& m = *impl_;
  int rank = 0, size = 1;
  mpi_check(MPI_Comm_rank(m.cart, &rank), "MPI_Comm_rank");
  mpi_check(MPI_Comm_size(m.cart, &size), "MPI_Comm_size");
  std::vector<int> counts(static_cast<size_t>(size)), offsets(static_cast<size_t>(size));
  const int count = static_cast<int>(mine.size());
  mpi_check(MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, m.cart), "MPI_Gather");
  std::vector<double> all;
  if (rank == 0) {
    for (int p = 1; p < size; ++p) offsets[static_cast<size_t>(p)] = offsets[static_cast<size_t>(p) - 1] + counts[static_cast<size_t>(p) - 1];
    all.resize(static_cast<size_t>(offsets.back() + counts.back()));
  }
  mpi_check(MPI_Gatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, 0, m.cart), "MPI_Gatherv");
  if (rank != 0) return {};
  // each rank's block, by its coordinates, into the whole grid
  std::vector<double> grid(static_cast<size_t>(m.rows) * static_cast<size_t>(m.cols));
  for (int p = 0; p < size; ++p) {
    int at[2];
    mpi_check(MPI_Cart_coords(m.cart, p, 2, at), "MPI_Cart_coords");
    const auto [row0, nrows] = share(m.rows, m.dims[0], at[0]);
    const auto [col0, ncols] = share(m.cols, m.dims[1], at[1]);
    const double* from = all.data() + offsets[static_cast<size_t>(p)];
    for (int a = 0; a < nrows; ++a)
      std::copy(from + static_cast<std::ptrdiff_t>(a) * ncols, from + static_cast<std::ptrdiff_t>(a + 1) * ncols,
                grid.begin() + static_cast<std::ptrdiff_t>(row0 + a) * m.cols + col0);
  }
  return grid;
}

}  // namespace stepwise
