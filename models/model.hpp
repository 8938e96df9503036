// A model: a pure description of one physical system. Parameters (constant), a named state layout,
// the right-hand side and Jacobian, an invariant, and the exact solution where one exists.
// It never steps, prints or draws.
#pragma once

#include <stepwise/models/shapes.hpp>
#include <stepwise/solvers/ode_system.hpp>

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace stepwise {

// what values a parameter may take
enum class Bound { finite, positive, nonnegative, unit_interval, flag };  // flag: 0 or 1

struct ParamSpec {
  std::string_view key;
  double default_value;
  std::string_view unit;
  std::string_view meaning;
  Bound bound = Bound::finite;
};

using Params = std::map<std::string, double, std::less<>>;

// a parameter that is unknown or out of range; key names it
struct BadParameter : std::invalid_argument {
  BadParameter(std::string key_, const std::string& message) : std::invalid_argument(message), key(std::move(key_)) {}
  std::string key;
};

class Model : public OdeSystem {
 public:
  virtual std::string_view name() const = 0;
  // one name per state entry, as trajectory.csv and summary.json write them
  virtual std::vector<std::string> state_names() const = 0;
  virtual Eigen::VectorXd initial_state() const = 0;
  // the quantity the physics conserves (or dissipates), where there is one
  virtual std::optional<double> energy(const Eigen::VectorXd& y) const { (void)y; return std::nullopt; }
  // a model whose state is too large to write entry by entry (a particle system) names the summary
  // quantities trajectory.csv and summary.json's final_state carry instead; empty: the state itself
  virtual std::vector<std::string> summary_names() const { return {}; }
  virtual Eigen::VectorXd summary(const Eigen::VectorXd& y) const { return y; }
  // exact solution y(t) where one is known for these parameters
  virtual bool has_exact() const { return false; }
  virtual Eigen::VectorXd exact(double t) const;
  // what the state y looks like in space (for render/); none for a model with nothing to show
  virtual std::optional<Shapes> shapes(const Eigen::VectorXd& y) const { (void)y; return std::nullopt; }
};


// a node of a grid model: row, column
using GridNode = std::array<int, 2>;

struct ModelInfo {
  std::string_view name;
  std::string_view description;
  std::span<const ParamSpec> params;
  std::function<std::unique_ptr<Model>(const Params&)> make;
  // for a model that takes a triangle mesh from the scene (its [mesh] table); make uses a default one.
  // Throws BadParameter with key "mesh" for a mesh the model cannot use
  std::function<std::unique_ptr<Model>(const Params&, const TriangleMesh&)> make_with_mesh = nullptr;
  // for a model on a grid that pins the nodes a scene lists (its [pins] table), besides those its parameters
  // pin. Throws BadParameter with key "pins" for a node off the grid
  std::function<std::unique_ptr<Model>(const Params&, std::span<const GridNode>)> make_with_pins = nullptr;
  // the columns the model's trajectory writes (its state's or its summary's entries), from the parameters alone,
  // for a model whose size the parameters set: the output budget is then checked before the model is made, so a
  // run refused for its output costs nothing (building a large model first takes seconds and its memory)
  std::function<double(const Params&)> output_columns = nullptr;
};

std::span<const ModelInfo> models();
const ModelInfo* find_model(std::string_view name);

// defaults overlaid by `values`; throws BadParameter for an unknown key or a value out of its bound
Params resolve_params(const ModelInfo& model, const Params& values);

// resolve_params then make
std::unique_ptr<Model> make_model(std::string_view name, const Params& values = {});

}  // namespace stepwise
