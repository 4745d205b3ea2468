#pragma once
// The residual loop's stages (analysis/loop/ only): a step's choice of refits, the refits
// themselves with their verdicts (loop_refits.cpp), and the structure check
// (structure_check.cpp). run_residual_loop (residual_loop.cpp) strings them together.
// Free functions; `say` is called on the caller's thread; run_refits runs fit_model on
// threads of its own (LoopOptions::parallel_refits), joined before it returns.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/fit/fitting.h"
#include "analysis/loop/residual_loop.h"

namespace doorbench::loop_detail {

using Say = std::function<void(const std::string&)>;

// "step N: the residual ranks a (12.3%, z 4.5), ..." (the best four).
std::string ranking_line(int step_number, const ResidualExamination& examination);

// The fit options of a refit with `kind` added to a model fitted with `current`: the
// effect's parameters free (appended when the free set is an explicit list) except those in
// options.fixed_effect_parameters; the latch not read off the data again.
FitOptions refit_options(const FitOptions& current, const LoopOptions& options, effects::Kind kind);

// Who is refitted: the candidates whose linear share and z pass, in rank order, then those
// the second look promotes, while refit slots are left; and every candidate whose kind is in
// `reexamine` (effects added before a family switch), beyond the slots. Gives the others
// their verdicts. Returns candidate indices.
std::vector<std::size_t> select_refits(ResidualExamination& examination, const LoopOptions& options,
                                       int step_number, const std::vector<effects::Kind>& reexamine,
                                       const Say& say);

// The refits of one step, each judged against `current` (CandidateEvidence::after, verdict,
// qualifies, parameters). `family_start` is the start model of the current family (the
// RefitStart::kStartModel start's base values). Returns the refits by candidate index (empty
// where a refit failed or the parent's fit stands); adds the fit_model calls to `fits`.
std::vector<std::optional<FitResult>> run_refits(
    const DoorModel& family_start, const FitResult& current, const FitOptions& current_options,
    const PreparedData& data, const LoopOptions& options, const std::vector<std::size_t>& to_refit,
    ResidualExamination& examination, int& fits, const Say& say, int step_number);

// The qualifying candidate with the lowest held-out RMSE; -1 when none qualifies.
int choose(const std::vector<CandidateEvidence>& candidates);

// The structure check's fit options for the other family `other`.
FitOptions structure_fit_options(const LoopOptions& options, ModelKind other);

// Whether the structure check is due now (LoopOptions::structure_check): `figures` of the
// current model, `last` its examination (with the step's refits judged, if any). Sets the
// check's reason, noise floor and best share either way.
bool structure_check_due(const LoopOptions& options, const ModelFigures& figures,
                         const ResidualExamination& last, StructureCheck& check);

// The structure check, once due: the other family fitted, compared with `current`, and
// examined for what it leaves (`other_examination`, which the loop reuses when it switches).
// Counts its fit in `fits`.
StructureCheck check_structure(StructureCheck check, const FitResult& current,
                               const PreparedData& data, const LoopOptions& options, int& fits,
                               const Say& say, ResidualExamination& other_examination);

}  // namespace doorbench::loop_detail
