// vkloc: the bench (CMake target vkloc::bench) in one include: the sequence simulator and its
// trajectories, the built-in demo models, trajectory evaluation, reports and edge overlays, and
// importers of other datasets (TUM RGB-D, EuRoC, ViSP). Includes vkloc/vkloc.hpp.
#pragma once

#include "vkloc/eval/eval.hpp"
#include "vkloc/eval/overlay.hpp"
#include "vkloc/eval/report.hpp"
#include "vkloc/io/import.hpp"
#include "vkloc/sim/demo_models.hpp"
#include "vkloc/sim/simulate.hpp"
#include "vkloc/sim/trajectory.hpp"
#include "vkloc/vkloc.hpp"
