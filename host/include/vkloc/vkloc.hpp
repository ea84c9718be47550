// vkloc: the whole library an integrator links (CMake target vkloc::vkloc) in one include.
//
//   core      Status/Result, Pose and SE(3)/SO(3), cameras, images, text and file helpers
//   model     triangle-mesh models: loading (OBJ, PLY, glTF/GLB, Draco, ViSP .cao), writing
//   render    the Renderer interface and the CPU reference renderer
//   track     live edges, keyframe edge points, Gauss-Newton edge alignment, tracking backends
//   fusion    IMU readings, integration, inertial prediction and the error-state EKF
//   localize  the Localizer and its parts (keyframes, motion prior, initializer)
//   io        image files, sequences, calibration files
//   engine    Vulkan: device, GPU renderer, GPU edge stages, the Accelerator of a device
//
// The bench (simulator, demo models, evaluation, dataset importers; vkloc::bench) has its own
// umbrella, vkloc/bench.hpp. Every function that can fail returns Result<T> or Status; nothing
// throws across the API, prints, or reads the environment.
#pragma once

#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/lens_camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/random.hpp"
#include "vkloc/core/remap.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/engine/gpu.hpp"
#include "vkloc/engine/gpu_accelerator.hpp"
#include "vkloc/engine/gpu_edges.hpp"
#include "vkloc/engine/gpu_remap.hpp"
#include "vkloc/fusion/error_state_ekf.hpp"
#include "vkloc/fusion/imu_integration.hpp"
#include "vkloc/fusion/inertial_predictor.hpp"
#include "vkloc/fusion/sensors.hpp"
#include "vkloc/io/calibration.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/localize/camera_front.hpp"
#include "vkloc/localize/initializer.hpp"
#include "vkloc/localize/keyframe.hpp"
#include "vkloc/localize/keyframe_manager.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/localize/motion_prior.hpp"
#include "vkloc/model/cao.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/model/model_write.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/track/edge_backend.hpp"
#include "vkloc/track/edge_detector.hpp"
#include "vkloc/track/edge_tracker.hpp"
#include "vkloc/track/live_frame.hpp"
#include "vkloc/track/reference_edges.hpp"
