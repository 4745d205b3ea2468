#pragma once
// One inverse design, stage by stage (analysis/design/ only): inverse_design() reads as the
// list of DesignRun's public stages. The stages of the smallest change are inverse_design.cpp,
// the sparse search's sparse_search.cpp, the maths they use internal/design_maths.h. A run
// holds references to its inputs and its result, which must outlive it; one thread.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/design/internal/design_maths.h"

namespace doorbench::design_detail {

class DesignRun {
 public:
  DesignRun(const DoorModel& asis, const PreparedData& data, const InverseDesignOptions& options,
            const std::vector<CommandedTorque>& commanded, InverseDesignResult& result)
      : asis_(asis), data_(data), options_(options), commanded_(commanded), result_(result) {}

  // The free set, scales, costs of change and priors; the noise levels.
  void set_up();
  // Sparse search, then the smallest change beside it (recordings of a door).
  void sparse_then_smallest_change();
  // The smallest change from several starts, then the fewest-changes search (playbacks).
  void smallest_change_then_fewest();
  // Notes on how well the first design fits.
  void note_fit_quality();

 private:
  // A fit of the design from `start` with `held` at AS-IS, counted in the result's fits and
  // times.
  DesignSolution fit_design(const DoorModel& start, int start_index,
                            const std::vector<std::string>& held);
  // The same fit on `threads` threads (0: the fit options'), neither counted nor timed: safe
  // to call from several threads at once (the result is the same on any number of threads).
  DesignSolution fit_only(const DoorModel& start, int start_index,
                          const std::vector<std::string>& held, int threads) const;
  void add_fit_times(const DesignSolution& solution);
  DesignFitter fitter() {
    return [this](const DoorModel& start, int index, const std::vector<std::string>& held) {
      return fit_design(start, index, held);
    };
  }
  void set_priors(double lambda);
  std::vector<DesignSolution> run_starts(const DoorModel& origin, int pass, int starts);
  DesignSolution as_is_design();
  DesignSolution sparse_search();
  bool sparse_step(std::vector<int>& chosen, DesignSolution& current);
  std::vector<std::pair<int, DesignSolution>> fit_candidates(const std::vector<int>& chosen,
                                                             const std::vector<int>& order,
                                                             const DesignSolution& current);
  void refine_sparse(std::vector<int>& chosen, DesignSolution& current);
  // The sparse design with one of its parts swapped for a candidate its step could not tell
  // from it, refitted (DesignSolution::swapped): into sparse_swaps_.
  void sparse_swaps(const std::vector<int>& chosen, const DesignSolution& current);
  // Keeps the swaps that fit like the sparse design and differ from every solution kept.
  void keep_sparse_swaps();
  std::optional<DesignSolution> refit_set(const DesignSolution& current, int reset_position,
                                          const std::vector<int>& set, const std::string& what);
  void keep_equivalent(const std::vector<DesignSolution>& found, const DesignSolution* reference);
  std::vector<std::string> names_except(const std::vector<int>& free_positions) const;
  // The felt quantities of `model` that miss their JND of the TO-BE recordings' (along their
  // motion; InverseDesignOptions::felt_jnds).
  std::vector<FeltMiss> felt_misses(const DoorModel& model) const;
  // Adds `name` to result.parts_tried when it is not there yet.
  void note_part_tried(const std::string& name);

  const DoorModel& asis_;
  const PreparedData& data_;
  const InverseDesignOptions& options_;
  const std::vector<CommandedTorque>& commanded_;
  InverseDesignResult& result_;
  Setup setup_;
  FitOptions fit_;
  double lambda_ = 0.0;
  double angle_noise_rad_ = 0.0;
  std::vector<std::string> start_notes_;
  const DesignSolution* best_ = nullptr;  // the best data cost among the solutions found
  std::vector<DesignSolution> found_;
  std::vector<std::string> sparse_held_;  // the free parameters the sparse design keeps
  std::vector<DesignSolution> sparse_swaps_;
};

}  // namespace doorbench::design_detail
