// The table of every method (docs/methods.md), made once from what each family file registers, in the order
// `stepwise methods`, methods.csv and the report's sweeps list them. The one place a method's name is
// looked up: the command line, the report, the tests and the benches all come here.
#pragma once

#include <stepwise/solvers/method.hpp>

#include <functional>
#include <memory>
#include <string_view>
#include <vector>

namespace stepwise {

const std::deque<Method>& methods();
// nullptr for a name not in the table
const Method* find_method(std::string_view name);
// the methods `keep` keeps, in the table's order: how a study chooses its methods, by what the table says of
// them (family, source, stepping, order, what is known of their stability), not by spelling their names
std::vector<const Method*> methods_where(const std::function<bool(const Method&)>& keep);

// a method defined outside the library's families (a program's own, a test's) added at the table's end, as a
// family's file adds its methods: `stepwise methods`, the command line's options, Python and the report's sweeps
// then see it as any other. std::logic_error as MethodTable::add
void add_method(Method method);

// the integrator for one run: BadMethod for an unknown name or a step control the method cannot use
std::unique_ptr<Integrator> make_integrator(std::string_view method, const StepControl& control);

}  // namespace stepwise
