#include "distributed_wave.hpp"

#include "fixed_step.hpp"
#include "mpi_support.hpp"
#include "run_support.hpp"

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

void DistributedWave::load(const double* z) {
  Impl& m = *impl_;
  for (int a = 0; a < m.block.rows; ++a)
    std::copy(z + static_cast<std::ptrdiff_t>(a) * m.block.cols, z + static_cast<std::ptrdiff_t>(a + 1) * m.block.cols,
              m.z.begin() + static_cast<std::ptrdiff_t>(a + 1) * m.stride + 1);
  exchange();
}

void DistributedWave::exchange() {
  MPI_Request requests[8];
  impl_->exchange(requests);
  mpi_check(MPI_Waitall(8, requests, MPI_STATUSES_IGNORE), "MPI_Waitall");
}

Eigen::VectorXd DistributedWave::gather_state(const Eigen::VectorXd& y) const {
  const Impl& m = *impl_;
  const auto cells = static_cast<std::ptrdiff_t>(m.block.rows) * m.block.cols;
  const std::vector<double> z = gather(std::vector<double>(y.data(), y.data() + cells));
  const std::vector<double> v = gather(std::vector<double>(y.data() + cells, y.data() + 2 * cells));
  if (z.empty()) return {};
  Eigen::VectorXd whole(static_cast<Eigen::Index>(z.size() + v.size()));
  std::copy(z.begin(), z.end(), whole.data());
  std::copy(v.begin(), v.end(), whole.data() + z.size());
  return whole;
}

double DistributedWave::max_over_ranks(double mine) const {
  double all = 0;
  mpi_check(MPI_Allreduce(&mine, &all, 1, MPI_DOUBLE, MPI_MAX, impl_->cart), "MPI_Allreduce");
  return all;
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

namespace {

// f(cell in the block, the same cell in the level inside its halo) for the block's cells on the grid's interior
template <class F>
void for_interior(const DistributedWave& grid, int points, F&& f) {
  const auto b = grid.block();
  const int stride = grid.stride();
  const int a0 = std::max(0, 1 - b.row0), a1 = std::min(b.rows, points - 1 - b.row0);
  const int c0 = std::max(0, 1 - b.col0), c1 = std::min(b.cols, points - 1 - b.col0);
  for (int a = a0; a < a1; ++a)
    for (int c = c0; c < c1; ++c) f(static_cast<std::ptrdiff_t>(a) * b.cols + c, static_cast<std::ptrdiff_t>(a + 1) * stride + c + 1);
}

// the water model on this rank's block: its state (z, v) of the block, its f block_rhs (collective, like every
// call on the grid), its events the model's for the block
class BlockSystem final : public OdeSystem, public EventSource {
 public:
  BlockSystem(DistributedWave& grid, const WaveGridView& view, const WaveBlocksView& blocks)
      : grid_(grid), view_(view), cells_(static_cast<Eigen::Index>(grid.block().rows) * grid.block().cols), events_(blocks.events(grid.block())) {}
  int size() const override { return static_cast<int>(2 * cells_); }
  bool autonomous() const override { return true; }
  std::span<const Event> events() const override { return events_; }
  const void* capability(const std::type_info& type) const override { return offer(type, as_part<EventSource>(*this)); }
  void rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override {
    block_rhs(grid_, view_, y.data(), dydt.data());
  }

 private:
  DistributedWave& grid_;
  WaveGridView view_;
  Eigen::Index cells_;
  std::vector<Event> events_;
};

// wave-fd's stepper (three_level_wave.hpp) on the block: the same decisions (continue the scheme, or restart
// by velocity Verlet), the same per-cell formulas
class BlockWaveFd final : public FixedStepper {
 public:
  BlockWaveFd(DistributedWave& grid, const WaveGridView& view, const CountedSystem& system)
      : grid_(grid), view_(view), system_(system), cells_(static_cast<Eigen::Index>(grid.block().rows) * grid.block().cols), z_prev_(cells_) {}

  bool step(double t, double h, const Eigen::VectorXd& y, Eigen::VectorXd& y_next, std::string&) override {
    ++system_.stats().rhs_evals;  // one Laplacian per step
    const double* z = y.data();
    const double* v = z + cells_;
    double* z1 = y_next.data();
    double* v1 = z1 + cells_;
    // the grid's boundary holds still: z = v = 0 there, the rest is written below
    const auto b = grid_.block();
    const auto still = [&](int a, int c) { z1[static_cast<std::ptrdiff_t>(a) * b.cols + c] = v1[static_cast<std::ptrdiff_t>(a) * b.cols + c] = 0; };
    for (const int edge : {0, view_.points - 1}) {
      if (edge >= b.row0 && edge < b.row0 + b.rows)
        for (int c = 0; c < b.cols; ++c) still(edge - b.row0, c);
      if (edge >= b.col0 && edge < b.col0 + b.cols)
        for (int a = 0; a < b.rows; ++a) still(a, edge - b.col0);
    }
    RunningNorm largest;  // of what is written below (the boundary's zeros change nothing)
    grid_.load(z);
    const double* level = grid_.level();
    const int stride = grid_.stride(), points = view_.points;
    const bool continuing = history_ && std::abs(h - h_) <= 1e-9 * h_ && std::abs(t - t_last_) <= 1e-9 * h_ && y.data() == last_;
    if (continuing) {
      for_interior(grid_, points, [&](std::ptrdiff_t j, std::ptrdiff_t at) {
        z1[j] = wave_cell(k_, z[j], z_prev_[j], neighbour_sum(level, at, stride));
        v1[j] = wave_velocity(h_, z1[j], z[j], z_prev_[j]);
        z_prev_[j] = z[j];
        largest.add(z1[j]);
        largest.add(v1[j]);
      });
    } else {
      const double c2 = view_.c * view_.c / (view_.spacing * view_.spacing);
      for_interior(grid_, points, [&](std::ptrdiff_t j, std::ptrdiff_t at) {
        const double a = wave_acceleration(c2, view_.mu, neighbour_sum(level, at, stride), z[j], v[j]);
        z_prev_[j] = z[j];
        const auto [zj, vj] = wave_restart_first(h, a, z[j], v[j]);
        z1[j] = zj;
        v1[j] = vj;
        largest.add(zj);
      });
      grid_.load(z1);
      for_interior(grid_, points, [&](std::ptrdiff_t j, std::ptrdiff_t at) {
        v1[j] = wave_restart_second(h, view_.mu, v1[j], wave_laplacian(c2, neighbour_sum(level, at, stride), z1[j]));
        largest.add(v1[j]);
      });
      h_ = h;
      k_ = wave_coefficients(view_, h);
    }
    history_ = true;
    t_last_ = t + h;
    last_ = y_next.data();
    norm_ = grid_.max_over_ranks(largest.value());
    return true;
  }
  void reset() override { history_ = false; }
  double norm(const Eigen::VectorXd& y) const override { return grid_.max_over_ranks(y.lpNorm<Eigen::Infinity>()); }

 private:
  DistributedWave& grid_;
  WaveGridView view_;
  const CountedSystem& system_;
  Eigen::Index cells_;
  Eigen::VectorXd z_prev_;  // z^{k-1} of the block, valid while history_
  bool history_ = false;
  double h_ = 0, t_last_ = 0;
  const double* last_ = nullptr;
  WaveCoefficients k_;
};

}  // namespace

void block_rhs(DistributedWave& grid, const WaveGridView& view, const double* y, double* dydt, bool stiff, bool damping) {
  const auto b = grid.block();
  const std::ptrdiff_t cells = static_cast<std::ptrdiff_t>(b.rows) * b.cols;
  const double *z = y, *v = y + cells;
  double *dz = dydt, *dv = dydt + cells;
  if (stiff) grid.load(z);
  const double* level = grid.level();
  const int stride = grid.stride();
  const double c2 = stiff ? view.c * view.c / (view.spacing * view.spacing) : 0.0, mu = damping ? view.mu : 0.0;
  for (std::ptrdiff_t k = 0; k < cells; ++k) {
    dz[k] = stiff ? v[k] : 0.0;
    dv[k] = 0.0;  // the boundary's; the interior's below
  }
  for_interior(grid, view.points, [&](std::ptrdiff_t cell, std::ptrdiff_t at) {
    dv[cell] = wave_acceleration(c2, mu, stiff ? neighbour_sum(level, at, stride) : 0.0, z[cell], v[cell]);
  });
}

RunResult wave_fd_distributed(DistributedWave& grid, const WaveGridView& view, const WaveBlocksView& blocks, const StepControl& control,
                              std::span<const double> t_out) {
  static const Method method{.name = "wave-fd",
                             .family = Family::wave_fd,
                             .source = Source::hand_written,
                             .description = "the seeds' three-level scheme on a rank's block of the grid",
                             .stepping = Stepping::fixed};
  const BlockSystem system(grid, view, blocks);
  const FixedStepIntegrator integrator(method, control, [&](const CountedSystem& s) { return std::make_unique<BlockWaveFd>(grid, view, s); });
  return integrator.integrate(system, 0.0, blocks.initial_state(grid.block()), t_out);
}

}  // namespace stepwise
