#include "projected_model.hpp"

#include "solvers/constraint_solver.hpp"

namespace stepwise {
namespace {

class ProjectedModel final : public Model, public Projection {
 public:
  explicit ProjectedModel(std::unique_ptr<Model> model) : m_(std::move(model)), c_(m_->as<DistanceConstraints>()->rigid()) {}

  void project(Eigen::Ref<Eigen::VectorXd> y) const override {
    // a solver a call: a sweep's threads share the model, and the solver keeps its factorisation
    ConstraintSolver solver(c_);
    double* x = y.data();
    Directions along;
    solver.directions(x, along);
    std::string ignored;  // a state that cannot be met is left as the method made it, and its drift shows
    if (solver.meet(x, along, nullptr, 1.0, ignored)) solver.tangent(x + y.size() / 2);
  }

  std::string_view name() const override { return m_->name(); }
  int size() const override { return m_->size(); }
  bool autonomous() const override { return m_->autonomous(); }
  std::vector<std::string> state_names() const override { return m_->state_names(); }
  Eigen::VectorXd initial_state() const override { return m_->initial_state(); }
  void rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> dydt) const override { m_->rhs(t, y, dydt); }
  // the model's capabilities (its Jacobians, events, ...), this wrapper's projection in place of any of its own
  const void* capability(const std::type_info& type) const override {
    return type == typeid(Projection) ? &as_part<Projection>(*this) : m_->capability(type);
  }
  std::optional<double> energy(const Eigen::VectorXd& y) const override { return m_->energy(y); }
  std::vector<std::string> summary_names() const override { return m_->summary_names(); }
  Eigen::VectorXd summary(const Eigen::VectorXd& y) const override { return m_->summary(y); }
  bool has_exact() const override { return m_->has_exact(); }
  Eigen::VectorXd exact(double t) const override { return m_->exact(t); }
  std::optional<Shapes> shapes(const Eigen::VectorXd& y) const override { return m_->shapes(y); }

 private:
  std::unique_ptr<Model> m_;
  DistanceConstraints c_;  // the rigid constraints, met after each step
};

}  // namespace

std::unique_ptr<Model> projected(std::unique_ptr<Model> model) { return std::make_unique<ProjectedModel>(std::move(model)); }

}  // namespace stepwise
