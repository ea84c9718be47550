// vkloc: how many threads a parallel stage of this process may use.
#pragma once

namespace vkloc {

/// The cores this process may run on: its CPU affinity mask where the system reports one (a
/// `taskset` or a container's cpuset), else std::thread::hardware_concurrency(); at least 1 and
/// at most 64.
int availableCores();

}  // namespace vkloc
