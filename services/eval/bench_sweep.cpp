// Sweeps over the bench's settings (bench_sweep.hpp).
#include "eval/bench_sweep.hpp"

#include <fmt/format.h>

#include <functional>
#include <set>
#include <stdexcept>

#include "core/base/enum_names.hpp"
#include "core/io/json.hpp"

namespace fs = std::filesystem;

namespace pbnbv::eval {

namespace {

// One swept setting: its option's name and, per value, the text of its label and how a spec takes it.
struct Axis {
  std::string name;
  std::vector<std::string> labels;
  std::string list;  // the values as the option takes them
  std::vector<std::function<void(BenchSpec&)>> apply;
};

template <typename T, typename Label>
Axis axis(const std::string& name, const std::vector<T>& values, Label label, void (*set)(BenchSpec&, const T&),
          std::string (*given)(const T&)) {
  if (values.empty()) throw std::invalid_argument("--" + name + ": no value");
  Axis a;
  a.name = name;
  for (const T& v : values) {
    const std::string text = label(v);
    a.list += (a.list.empty() ? "" : ",") + given(v);
    for (const std::string& before : a.labels) {
      if (before == text) throw std::invalid_argument("--" + name + ": '" + text + "' is listed twice");
    }
    a.labels.push_back(text);
    a.apply.push_back([v, set](BenchSpec& s) { set(s, v); });
  }
  return a;
}

template <typename E>
std::string named(const E& e) {
  return std::string(name_of(e));
}

}  // namespace

Sweep expand_sweep(const BenchSpec& base, const SweepValues& v) {
  std::vector<Axis> axes;
  const auto real = [](const double& r) { return fmt::format("{}", r); };
  const auto whole = [](const int& n) { return std::to_string(n); };
  axes.push_back(axis<RigKind>("rig", v.rigs, named<RigKind>, [](BenchSpec& s, const RigKind& r) { s.rig = r; }, named<RigKind>));
  axes.push_back(axis<std::string>(
      "rig-model", v.rig_models, [](const std::string& m) { return m.empty() ? std::string("default") : fs::path(m).stem().string(); },
      [](BenchSpec& s, const std::string& m) { s.rig_model = m; }, [](const std::string& m) { return m; }));
  axes.push_back(axis<CameraKind>("camera", v.cameras, named<CameraKind>, [](BenchSpec& s, const CameraKind& c) { s.camera = c; },
                                  named<CameraKind>));
  axes.push_back(axis<RigErrors>("rig-errors", v.rig_errors, named<RigErrors>,
                                 [](BenchSpec& s, const RigErrors& e) { s.rig_errors = e; }, named<RigErrors>));
  axes.push_back(axis<double>("resolution", v.resolutions, real, [](BenchSpec& s, const double& r) { s.resolution_m = r; }, real));
  axes.push_back(axis<int>("first-views", v.first_views, whole, [](BenchSpec& s, const int& n) { s.first_views = n; }, whole));
  Sweep sweep;
  sweep.out = base.out;
  for (const Axis& a : axes) {
    if (a.labels.size() < 2) continue;
    sweep.parameters.push_back(a.name);
    sweep.lists[a.name] = a.list;
  }
  std::vector<std::size_t> at(axes.size(), 0);  // the combination: a value of each axis
  while (true) {
    BenchSpec s = base;
    std::string label;
    std::vector<std::string> values;
    for (std::size_t k = 0; k < axes.size(); ++k) {
      axes[k].apply[at[k]](s);
      if (axes[k].labels.size() < 2) continue;
      label += (label.empty() ? "" : ",") + axes[k].name + "=" + axes[k].labels[at[k]];
      values.push_back(axes[k].labels[at[k]]);
    }
    s.out = label.empty() ? base.out : base.out / label;
    try {
      s.validate();
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument((label.empty() ? std::string() : "the sweep's " + label + ": ") + e.what());
    }
    sweep.benches.emplace_back(label, std::move(s));
    sweep.values.push_back(std::move(values));
    std::size_t k = axes.size();
    while (k > 0 && ++at[k - 1] == axes[k - 1].labels.size()) at[--k] = 0;
    if (k == 0) break;
  }
  return sweep;
}

std::vector<BenchResult> run_sweep(const Sweep& sweep, const fs::path& self, std::ostream& log, bool terminal) {
  if (fs::exists(sweep.out / "bench.json")) {
    throw std::invalid_argument(sweep.out.string() + " holds a benchmark of its own (bench.json), not a sweep: use another --out");
  }
  fs::create_directories(sweep.out);
  std::vector<BenchResult> results = run_benches(sweep.benches, sweep.out, self, log, terminal);
  write_sweep(sweep, results);
  return results;
}

}  // namespace pbnbv::eval
