// Reports of a trajectory evaluation: terminal table, JSON and a self-contained HTML page whose
// plots are drawn by an inlined Chart.js.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "eval/report_quality.hpp"
#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/eval/report.hpp"

#ifndef VKLOC_CHARTJS_PATH
#define VKLOC_CHARTJS_PATH "/usr/share/javascript/chart.js/chart.min.js"
#endif

namespace vkloc {
namespace {

using nlohmann::json;

std::string nowIso8601() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  localtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S%z", &tm);
  return buf;
}

std::string writtenAt(const ReportInfo& info) { return info.written_at.empty() ? nowIso8601() : info.written_at; }

// Rounds for plots: 7 significant digits are more than a screen shows.
double r7(double v) {
  if (!std::isfinite(v) || v == 0.0) return v;
  const double mag = std::pow(10.0, 6 - std::floor(std::log10(std::abs(v))));
  return std::round(v * mag) / mag;
}

json statsJson(const ErrorStats& s) {
  return json{{"count", s.count}, {"mean", s.mean}, {"median", s.median},
              {"rmse", s.rmse},   {"max", s.max},   {"std", s.std}};
}

json vec3Json(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json alignmentJson(const Alignment& a) {
  json j{{"valid", a.valid},
         {"scale", a.scale},
         {"translation_m", statsJson(a.translation_m)},
         {"rotation_deg", statsJson(a.rotation_deg)}};
  j["T_gt_est"] = formatPose(a.T_gt_est);
  return j;
}

json markedJson(const std::vector<MarkedFrame>& frames) {
  json out = json::array();
  for (const auto& f : frames) out.push_back(f.t_ns);
  return out;
}

double seconds(int64_t t_ns, int64_t t0_ns) { return static_cast<double>(t_ns - t0_ns) * 1e-9; }

// Dumps JSON; invalid UTF-8 in strings (e.g. paths) is replaced instead of failing.
std::string dumpJson(const json& j, int indent, bool ascii) {
  return j.dump(indent, ' ', ascii, json::error_handler_t::replace);
}

std::string htmlEscape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// JSON made safe inside <script>: no '<', '>', '&' (so no "</script>" or "<!--"), ASCII only (so
// no U+2028/2029 line separators).
std::string scriptJson(const json& j) {
  const std::string s = dumpJson(j, -1, true);
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    if (c == '<') {
      out += "\\u003c";
    } else if (c == '>') {
      out += "\\u003e";
    } else if (c == '&') {
      out += "\\u0026";
    } else {
      out += c;
    }
  }
  return out;
}

// Library text inside <script>: break any "</script" or "<!--" (only possible inside string or
// regex literals, where "<\/" and "<\!" mean the same).
std::string scriptText(const std::string& s) {
  std::string out;
  out.reserve(s.size() + 16);
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '<' && i + 1 < s.size() && (s[i + 1] == '/' || s[i + 1] == '!')) {
      const std::string next = s.substr(i + 1, 7);
      std::string low = next;
      for (char& c : low) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (low.rfind("/script", 0) == 0 || low.rfind("!--", 0) == 0) {
        out += "<\\";
        continue;
      }
    }
    out += s[i];
  }
  return out;
}

// Every k-th index so that at most `limit` remain (the last one always kept).
std::vector<size_t> decimate(size_t n, size_t limit) {
  std::vector<size_t> idx;
  if (n == 0) return idx;
  const size_t step = std::max<size_t>(1, (n + limit - 1) / limit);
  for (size_t i = 0; i < n; i += step) idx.push_back(i);
  if (idx.back() != n - 1) idx.push_back(n - 1);
  return idx;
}

json histogram(const std::vector<double>& values) {
  json h{{"centres", json::array()}, {"counts", json::array()}};
  if (values.empty()) return h;
  const double hi = *std::max_element(values.begin(), values.end());
  const size_t bins = std::clamp<size_t>(static_cast<size_t>(std::sqrt(static_cast<double>(values.size()))), 5, 40);
  const double width = hi > 0 ? hi / static_cast<double>(bins) : 1.0;
  std::vector<size_t> counts(bins, 0);
  for (double v : values) {
    counts[std::min(bins - 1, static_cast<size_t>(std::max(0.0, v) / width))]++;
  }
  for (size_t b = 0; b < bins; ++b) {
    h["centres"].push_back(r7((static_cast<double>(b) + 0.5) * width));
    h["counts"].push_back(counts[b]);
  }
  return h;
}

std::string num(double v, int decimals = 4) {
  if (!std::isfinite(v)) return "-";
  return fmt::format("{:.{}f}", v, decimals);
}

std::string pct(double fraction) { return fmt::format("{:.1f} %", 100.0 * fraction); }

// One row of the summary: label, unit and the statistics.
struct StatsRow {
  std::string label;
  const ErrorStats* stats;
};

std::vector<StatsRow> statsRows(const EvalResult& r) {
  std::vector<StatsRow> rows{{"translation (m)", &r.translation_m}, {"rotation (deg)", &r.rotation_deg}};
  if (r.se3.valid) {
    rows.push_back({"SE(3)-aligned translation (m)", &r.se3.translation_m});
    rows.push_back({"SE(3)-aligned rotation (deg)", &r.se3.rotation_deg});
  }
  if (r.sim3 && r.sim3->valid) {
    rows.push_back(
        {fmt::format("Sim(3)-aligned translation (m, scale {:.4f})", r.sim3->scale), &r.sim3->translation_m});
  }
  const std::string d = fmt::format("{:g} m", r.rpe_distance.nominal);
  const std::string s = fmt::format("{:g} s", r.rpe_time.nominal);
  rows.push_back({"RPE over " + d + ": translation (%)", &r.rpe_distance.translation});
  rows.push_back({"RPE over " + d + ": rotation (deg/m)", &r.rpe_distance.rotation});
  rows.push_back({"RPE over " + s + ": translation (m/s)", &r.rpe_time.translation});
  rows.push_back({"RPE over " + s + ": rotation (deg/s)", &r.rpe_time.rotation});
  return rows;
}

const char* kStyle = R"CSS(
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:24px;color:#222;max-width:1400px}
h1{font-size:1.5em;margin-bottom:4px}h2{font-size:1.2em;margin-top:28px;border-bottom:1px solid #ccc}
h3{font-size:1em;margin:0 0 6px 0}
table{border-collapse:collapse;margin:8px 0}td,th{padding:3px 10px;border-bottom:1px solid #e4e4e4}
th{text-align:left;background:#f4f4f4}td.n{text-align:right;font-variant-numeric:tabular-nums}
.meta td{border:none;padding:1px 10px 1px 0;color:#444}.warn{color:#a33}
.notice{background:#fff3cd;border:1px solid #e0c060;padding:10px;border-radius:4px}
.grid{display:grid;grid-template-columns:repeat(auto-fit,minmax(560px,1fr));gap:18px}
.plot{border:1px solid #ddd;border-radius:4px;padding:10px}.plot canvas{width:100%}
.big{color:#0a5;font-size:1.3em;font-weight:600}
)CSS";

// Draws the plots from the data object D (see evalReportHtml).
const char* kPlotScript = R"JS(
(function(){
const pts=a=>a.map(p=>({x:p[0],y:p[1]}));
// Breaks a line where frames are missing: a gap over 3 median frame intervals gets a null point.
function gaps(p,t){if(t.length<3)return p;const dt=t.slice(1).map((v,i)=>v-t[i]).sort((a,b)=>a-b);
  const lim=3*dt[dt.length>>1];const out=[p[0]];
  for(let i=1;i<p.length;i++){if(t[i]-t[i-1]>lim)out.push({x:p[i].x,y:null});out.push(p[i]);}return out;}
const mark=(ts,y)=>ts.map(t=>({x:t,y:y}));
const base={animation:false,normalized:true,responsive:true,
  interaction:{mode:'nearest',intersect:false},
  plugins:{legend:{position:'top'},decimation:{enabled:false}}};
function opts(xt,yt,extra){return Object.assign({},base,{scales:{
  x:{type:'linear',title:{display:true,text:xt}},y:{type:'linear',title:{display:true,text:yt}}}},extra||{});}
function line(label,data,color,w){return {label:label,data:data,borderColor:color,backgroundColor:color,
  borderWidth:w||1.5,pointRadius:0,showLine:true,fill:false};}
function markers(label,data,color,style){return {label:label,data:data,borderColor:color,backgroundColor:color,
  pointRadius:5,pointStyle:style||'crossRot',borderWidth:2,showLine:false};}
function chart(id,cfg){const el=document.getElementById(id);if(el)new Chart(el,cfg);}
// Same metres per pixel on x and y.
const equalAxes={id:'equalAxes',afterLayout(c){
  if(c.$equal)return;const a=c.chartArea;const w=a.right-a.left,h=a.bottom-a.top;
  if(!(w>0&&h>0)||!D.bounds)return;const b=D.bounds;
  const cx=(b[0]+b[2])/2,cy=(b[1]+b[3])/2;
  const u=Math.max((b[2]-b[0])*1.05/w,(b[3]-b[1])*1.05/h,1e-9);
  const s=c.options.scales;s.x.min=cx-u*w/2;s.x.max=cx+u*w/2;s.y.min=cy-u*h/2;s.y.max=cy+u*h/2;
  c.$equal=true;c.update('none');c.$equal=false;}};
const topSets=[line('ground truth',pts(D.gt_xy),'#1f77b4',2),
  Object.assign(line('estimate',gaps(pts(D.est_xy),D.est_t),'#ff7f0e',1.2),{pointRadius:1.5})];
if(D.lost_xy.length)topSets.push(markers('lost',pts(D.lost_xy),'#d62728'));
if(D.inertial_xy.length)topSets.push(markers('IMU only',pts(D.inertial_xy),'#bcbd22','rect'));
if(D.not_estimated_xy.length)topSets.push(markers('not estimated',pts(D.not_estimated_xy),'#7f7f7f','triangle'));
const topOpts=opts('x (m)','y (m)',{aspectRatio:1});
topOpts.scales.x.ticks={includeBounds:false};topOpts.scales.y.ticks={includeBounds:false};
chart('topview',{type:'scatter',data:{datasets:topSets},options:topOpts,plugins:[equalAxes]});
function overTime(id,label,values,aligned,alignedLabel,unit,color){
  const sets=[line(label,gaps(pts(D.t.map((t,i)=>[t,values[i]])),D.t),color)];
  if(aligned)sets.push(line(alignedLabel,gaps(pts(D.t.map((t,i)=>[t,aligned[i]])),D.t),'#2ca02c',1));
  if(D.lost_t.length)sets.push(markers('lost',mark(D.lost_t,0),'#d62728'));
  if(D.inertial_t.length)sets.push(markers('IMU only',mark(D.inertial_t,0),'#bcbd22','rect'));
  if(D.not_estimated_t.length)sets.push(markers('not estimated',mark(D.not_estimated_t,0),'#7f7f7f','triangle'));
  chart(id,{type:'scatter',data:{datasets:sets},options:opts('time (s)',unit)});}
overTime('terr','translation error',D.terr,D.aligned_terr,'after SE(3) alignment','error (m)','#1f77b4');
overTime('rerr','rotation error',D.rerr,D.aligned_rerr,'after SE(3) alignment','error (deg)','#9467bd');
function hist(id,h,label,unit,color){chart(id,{type:'bar',data:{labels:h.centres.map(c=>+c.toPrecision(3)),
  datasets:[{label:label,data:h.counts,backgroundColor:color,barPercentage:1,categoryPercentage:1}]},
  options:Object.assign({},base,{scales:{x:{title:{display:true,text:unit}},y:{title:{display:true,text:'frames'}}}})});}
hist('thist',D.thist,'translation error','error (m), bin centre','#d62728');
hist('rhist',D.rhist,'rotation error','error (deg), bin centre','#9467bd');
const ax=['x','y','z'],axc=['#d62728','#2ca02c','#1f77b4'];
chart('axes',{type:'scatter',data:{datasets:ax.map((a,k)=>line(a+' (est - gt)',
  gaps(pts(D.t.map((t,i)=>[t,D.axis_err[k][i]])),D.t),axc[k]))},options:opts('time (s)','error (m)')});
if(D.timing){const cols=['#000','#1f77b4','#ff7f0e','#2ca02c','#d62728','#9467bd','#8c564b','#e377c2','#17becf'];
  chart('timing',{type:'scatter',data:{datasets:D.timing.stages.map((s,k)=>line(s.name,
    pts(D.timing.t.map((t,i)=>[t,s.values[i]])),cols[k%cols.length],s.name==='total_ms'?2:1))},
    options:opts('time (s)','milliseconds')});}
})();
)JS";

}  // namespace

const char* defaultChartJsPath() { return VKLOC_CHARTJS_PATH; }

Result<std::string> loadChartJs(const std::string& path) {
  Result<std::string> read = text::readFile(path, "Chart.js");
  if (!read.ok()) return read.error();
  std::string text = std::move(read).value();
  if (text.empty() || text.find("Chart") == std::string::npos) {
    return makeError(ErrorCode::kMalformedInput, fmt::format("{}: does not look like Chart.js", path));
  }
  return text;
}

Status writeReportFile(const std::string& path, const std::string& text) { return writeFileAtomically(path, text); }

std::string formatEvalTable(const EvalResult& r) {
  std::string o;
  o += fmt::format("estimates: {}, matched to ground truth: {} ({} interpolated), without ground truth: {}\n",
                   r.estimates, r.matched, r.interpolated, r.unmatched_t_ns.size());
  o += fmt::format("reference frames ({}): {}, localized {}, not estimated {} ({}), lost {} ({})\n", r.reference_source,
                   r.reference_frames, pct(r.localized_fraction), r.not_estimated.size(), pct(r.not_estimated_fraction),
                   r.lost.size(), pct(r.lost_fraction));
  if (!r.state_counts.empty()) {
    o += "frames-log states:";
    for (const auto& [state, n] : r.state_counts) o += fmt::format(" {} {}", state, n);
    o += "\n";
  }
  o += "\n";
  const auto rows = statsRows(r);
  size_t w = 8;
  for (const auto& row : rows) w = std::max(w, row.label.size());
  o += fmt::format("{:<{}} {:>7} {:>10} {:>10} {:>10} {:>10} {:>10}\n", "error", w, "n", "mean", "median", "rmse",
                   "max", "std");
  for (const auto& row : rows) {
    const ErrorStats& s = *row.stats;
    o += fmt::format("{:<{}} {:>7} {:>10} {:>10} {:>10} {:>10} {:>10}\n", row.label, w, s.count, num(s.mean),
                     num(s.median), num(s.rmse), num(s.max), num(s.std));
  }
  o += fmt::format("\n{:<{}} {:>10} {:>10} {:>10}\n", "per axis, no alignment (m)", w, "x", "y", "z");
  o += fmt::format("{:<{}} {:>10} {:>10} {:>10}\n", "  mean |error|", w, num(r.axis_mean_abs_m.x()),
                   num(r.axis_mean_abs_m.y()), num(r.axis_mean_abs_m.z()));
  o += fmt::format("{:<{}} {:>10} {:>10} {:>10}\n", "  rmse", w, num(r.axis_rmse_m.x()), num(r.axis_rmse_m.y()),
                   num(r.axis_rmse_m.z()));
  if (!r.timing.empty()) {
    o += fmt::format("\n{:<{}} {:>7} {:>10} {:>10} {:>10} {:>10}\n", "frame time (ms)", w, "n", "mean", "median", "p90",
                     "max");
    for (const auto& t : r.timing) {
      o += fmt::format("{:<{}} {:>7} {:>10} {:>10} {:>10} {:>10}\n", "  " + t.name, w, t.count, num(t.mean_ms, 2),
                       num(t.median_ms, 2), num(t.p90_ms, 2), num(t.max_ms, 2));
    }
    if (r.frame_rate_hz > 0) o += fmt::format("frame rate: {:.1f} Hz (1000 / median total_ms)\n", r.frame_rate_hz);
  }
  for (const auto& wmsg : r.warnings) o += "warning: " + wmsg + "\n";
  return o;
}

std::string evalReportJson(const EvalResult& r, const ReportInfo& info) {
  json j;
  j["format"] = "vkloc-eval-1";
  j["written_at"] = writtenAt(info);
  j["inputs"] = {{"estimate", info.estimate_path},
                 {"groundtruth", info.groundtruth_path},
                 {"sequence", info.sequence_path},
                 {"frames", info.frames_path}};
  j["options"] = {{"max_gap_s", r.options.max_gap_s},
                  {"max_time_diff_s", r.options.max_time_diff_s},
                  {"rpe_distance_m", r.options.rpe_distance_m},
                  {"rpe_delta_s", r.options.rpe_delta_s},
                  {"sim3", r.options.sim3}};
  json unmatched = json::array();
  for (int64_t t : r.unmatched_t_ns) unmatched.push_back(t);
  j["matching"] = {{"estimates", r.estimates},
                   {"matched", r.matched},
                   {"interpolated", r.interpolated},
                   {"without_groundtruth", r.unmatched_t_ns.size()},
                   {"without_groundtruth_t_ns", unmatched}};
  json states = json::object();
  for (const auto& [s, n] : r.state_counts) states[s] = n;
  j["frames"] = {{"reference_source", r.reference_source},
                 {"reference_frames", r.reference_frames},
                 {"localized_fraction", r.localized_fraction},
                 {"not_estimated", r.not_estimated.size()},
                 {"not_estimated_fraction", r.not_estimated_fraction},
                 {"not_estimated_t_ns", markedJson(r.not_estimated)},
                 {"lost", r.lost.size()},
                 {"lost_fraction", r.lost_fraction},
                 {"lost_t_ns", markedJson(r.lost)},
                 {"inertial", r.inertial.size()},
                 {"inertial_t_ns", markedJson(r.inertial)},
                 {"state_counts", states}};
  j["ate"] = {{"translation_m", statsJson(r.translation_m)},
              {"rotation_deg", statsJson(r.rotation_deg)},
              {"per_axis_m", {{"mean_abs", vec3Json(r.axis_mean_abs_m)}, {"rmse", vec3Json(r.axis_rmse_m)}}}};
  j["ate_se3"] = alignmentJson(r.se3);
  j["ate_sim3"] = r.sim3 ? alignmentJson(*r.sim3) : json(nullptr);
  j["rpe_distance"] = {{"segment_m", r.rpe_distance.nominal},
                       {"skipped", r.rpe_distance.skipped},
                       {"translation_percent", statsJson(r.rpe_distance.translation)},
                       {"rotation_deg_per_m", statsJson(r.rpe_distance.rotation)}};
  j["rpe_time"] = {{"segment_s", r.rpe_time.nominal},
                   {"skipped", r.rpe_time.skipped},
                   {"translation_m_per_s", statsJson(r.rpe_time.translation)},
                   {"rotation_deg_per_s", statsJson(r.rpe_time.rotation)}};
  json stages = json::array();
  for (const auto& t : r.timing) {
    stages.push_back({{"name", t.name},
                      {"count", t.count},
                      {"mean_ms", t.mean_ms},
                      {"median_ms", t.median_ms},
                      {"p90_ms", t.p90_ms},
                      {"max_ms", t.max_ms}});
  }
  j["timing"] = {{"stages", stages}, {"frame_rate_hz", r.frame_rate_hz}};
  json per_frame = json::array();
  for (const auto& f : r.frames) {
    per_frame.push_back({{"t_ns", f.t_ns},
                         {"t_s", seconds(f.t_ns, r.t0_ns)},
                         {"p_est", vec3Json(f.p_world_est)},
                         {"p_gt", vec3Json(f.p_world_gt)},
                         {"error_m", vec3Json(f.error_world)},
                         {"translation_m", f.translation_m},
                         {"rotation_deg", f.rotation_deg},
                         {"aligned_translation_m", f.aligned_translation_m},
                         {"aligned_rotation_deg", f.aligned_rotation_deg},
                         {"interpolated", f.interpolated},
                         {"gt_time_diff_s", f.gt_time_diff_s},
                         {"state", f.state}});
  }
  j["t0_ns"] = r.t0_ns;
  j["per_frame"] = per_frame;
  j["warnings"] = r.warnings;
  return dumpJson(j, 1, false) + "\n";
}

std::string evalReportHtml(const EvalResult& r, const ReportInfo& info, const std::string* chartjs_source) {
  // --- data for the plots (decimated to keep the page light)
  constexpr size_t kMaxPoints = 5000;
  json d;
  json gt_xy = json::array(), est_xy = json::array();
  double b[4] = {1e300, 1e300, -1e300, -1e300};
  auto grow = [&b](double x, double y) {
    b[0] = std::min(b[0], x);
    b[1] = std::min(b[1], y);
    b[2] = std::max(b[2], x);
    b[3] = std::max(b[3], y);
  };
  for (size_t i : decimate(r.groundtruth.size(), kMaxPoints)) {
    const Eigen::Vector3d p = r.groundtruth[i].T_world_camera.translation();
    gt_xy.push_back({r7(p.x()), r7(p.y())});
    grow(p.x(), p.y());
  }
  json est_t = json::array();
  for (size_t i : decimate(r.estimate.size(), kMaxPoints)) {
    const Eigen::Vector3d p = r.estimate[i].T_world_camera.translation();
    est_xy.push_back({r7(p.x()), r7(p.y())});
    est_t.push_back(r7(seconds(r.estimate[i].t_ns, r.t0_ns)));
    grow(p.x(), p.y());
  }
  d["gt_xy"] = gt_xy;
  d["est_xy"] = est_xy;
  d["est_t"] = est_t;
  d["bounds"] = b[0] <= b[2] ? json::array({b[0], b[1], b[2], b[3]}) : json(nullptr);
  auto marked = [&](const std::vector<MarkedFrame>& frames, json& xy, json& ts) {
    xy = json::array();
    ts = json::array();
    for (size_t i : decimate(frames.size(), kMaxPoints)) {
      const MarkedFrame& f = frames[i];
      ts.push_back(r7(seconds(f.t_ns, r.t0_ns)));
      if (f.has_gt) xy.push_back({r7(f.p_world_gt.x()), r7(f.p_world_gt.y())});
    }
  };
  marked(r.lost, d["lost_xy"], d["lost_t"]);
  marked(r.inertial, d["inertial_xy"], d["inertial_t"]);
  marked(r.not_estimated, d["not_estimated_xy"], d["not_estimated_t"]);
  json t = json::array(), te = json::array(), re = json::array(), ate = json::array(), are = json::array();
  json axis = json::array({json::array(), json::array(), json::array()});
  for (size_t i : decimate(r.frames.size(), kMaxPoints)) {
    const FrameError& f = r.frames[i];
    t.push_back(r7(seconds(f.t_ns, r.t0_ns)));
    te.push_back(r7(f.translation_m));
    re.push_back(r7(f.rotation_deg));
    ate.push_back(r7(f.aligned_translation_m));
    are.push_back(r7(f.aligned_rotation_deg));
    for (int k = 0; k < 3; ++k) axis[k].push_back(r7(f.error_world[k]));
  }
  d["t"] = t;
  d["terr"] = te;
  d["rerr"] = re;
  d["aligned_terr"] = r.se3.valid ? ate : json(nullptr);
  d["aligned_rerr"] = r.se3.valid ? are : json(nullptr);
  d["axis_err"] = axis;
  std::vector<double> tv, rv;
  for (const auto& f : r.frames) {
    tv.push_back(f.translation_m);
    rv.push_back(f.rotation_deg);
  }
  d["thist"] = histogram(tv);
  d["rhist"] = histogram(rv);
  const bool has_timing = r.frame_log && !r.frame_log->stage_names.empty() && !r.frame_log->t_ns.empty();
  if (has_timing) {
    const FrameLog& fl = *r.frame_log;
    json tt = json::array(), stages = json::array();
    const auto idx = decimate(fl.t_ns.size(), kMaxPoints);
    for (size_t i : idx) tt.push_back(r7(seconds(fl.t_ns[i], r.t0_ns)));
    for (size_t k = 0; k < fl.stage_names.size(); ++k) {
      json v = json::array();
      for (size_t i : idx) v.push_back(std::isfinite(fl.stage_ms[k][i]) ? json(r7(fl.stage_ms[k][i])) : json(nullptr));
      stages.push_back({{"name", fl.stage_names[k]}, {"values", v}});
    }
    d["timing"] = {{"t", tt}, {"stages", stages}};
  } else {
    d["timing"] = nullptr;
  }

  // --- page
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  h += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  const std::string title = info.estimate_path.empty() ? std::string("trajectory")
                                                       : std::filesystem::path(info.estimate_path).filename().string();
  h += "<title>vkloc eval: " + htmlEscape(title) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n";
  h += "<h1>Trajectory evaluation</h1>\n<table class=\"meta\">\n";
  auto meta = [&h](const char* k, const std::string& v) {
    if (!v.empty()) h += fmt::format("<tr><td>{}</td><td><code>{}</code></td></tr>\n", k, htmlEscape(v));
  };
  meta("estimate", info.estimate_path);
  meta("ground truth", info.groundtruth_path);
  meta("sequence", info.sequence_path);
  meta("frames log", info.frames_path);
  meta("written", writtenAt(info));
  h += "</table>\n";
  for (const auto& w : r.warnings) h += "<p class=\"warn\">warning: " + htmlEscape(w) + "</p>\n";

  h += "<h2>Summary</h2>\n";
  h += fmt::format(
      "<p><span class=\"big\">{}</span> of {} reference frames ({}) localized; not estimated {} ({}), lost {} "
      "({}), from the IMU alone {}.<br>{} estimates, {} with ground truth ({} interpolated), {} without.</p>\n",
      htmlEscape(pct(r.localized_fraction)), r.reference_frames, htmlEscape(r.reference_source), r.not_estimated.size(),
      htmlEscape(pct(r.not_estimated_fraction)), r.lost.size(), htmlEscape(pct(r.lost_fraction)), r.inertial.size(),
      r.estimates, r.matched, r.interpolated, r.unmatched_t_ns.size());
  h += "<table>\n<tr><th>error</th><th>n</th><th>mean</th><th>median</th><th>rmse</th><th>max</th><th>std</th></tr>\n";
  for (const auto& row : statsRows(r)) {
    const ErrorStats& s = *row.stats;
    h += fmt::format(
        "<tr><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td "
        "class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td></tr>\n",
        htmlEscape(row.label), s.count, num(s.mean), num(s.median), num(s.rmse), num(s.max), num(s.std));
  }
  h += "</table>\n<table>\n<tr><th>per axis, no alignment (m)</th><th>x</th><th>y</th><th>z</th></tr>\n";
  h += fmt::format(
      "<tr><td>mean |error|</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td></tr>\n",
      num(r.axis_mean_abs_m.x()), num(r.axis_mean_abs_m.y()), num(r.axis_mean_abs_m.z()));
  h += fmt::format(
      "<tr><td>rmse</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td></tr>\n</table>\n",
      num(r.axis_rmse_m.x()), num(r.axis_rmse_m.y()), num(r.axis_rmse_m.z()));
  if (!r.timing.empty()) {
    h += "<table>\n<tr><th>frame time (ms)</th><th>n</th><th>mean</th><th>median</th><th>p90</th><th>max</th></tr>\n";
    for (const auto& st : r.timing) {
      h += fmt::format(
          "<tr><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td "
          "class=\"n\">{}</td><td class=\"n\">{}</td></tr>\n",
          htmlEscape(st.name), st.count, num(st.mean_ms, 2), num(st.median_ms, 2), num(st.p90_ms, 2),
          num(st.max_ms, 2));
    }
    h += "</table>\n";
    if (r.frame_rate_hz > 0)
      h += fmt::format("<p>frame rate {:.1f} Hz (1000 / median total_ms)</p>\n", r.frame_rate_hz);
  }
  if (!r.state_counts.empty()) {
    h += "<p>frames-log states:";
    for (const auto& [state, n] : r.state_counts) h += fmt::format(" {} {};", htmlEscape(state), n);
    h += "</p>\n";
  }

  h += "<h2>Plots</h2>\n";
  if (chartjs_source == nullptr) {
    h += "<p class=\"notice\">Plots unavailable: Chart.js was not found when this report was written. Install the "
         "Debian package libjs-chart.js or pass <code>--chartjs PATH</code> to <code>vkloc eval</code>. The tables "
         "above are complete.</p>\n";
  } else {
    h += "<div class=\"grid\">\n";
    auto plot = [&h](const char* id, const char* caption) {
      h += fmt::format("<div class=\"plot\"><h3>{}</h3><canvas id=\"{}\"></canvas></div>\n", caption, id);
    };
    plot("topview", "Trajectory, top view (x-y, equal scale)");
    plot("terr", "Translation error over time");
    plot("rerr", "Rotation error over time");
    plot("axes", "Error per axis over time (no alignment)");
    plot("thist", "Translation error histogram");
    plot("rhist", "Rotation error histogram");
    if (has_timing) plot("timing", "Time per frame and stage");
    h += qualityPlotDivs(r.frame_log ? &*r.frame_log : nullptr);
    h += "</div>\n";
    h += "<script>\n" + scriptText(*chartjs_source) + "\n</script>\n";
    h += "<script>\nconst D=" + scriptJson(d) + ";\n" + kPlotScript + "</script>\n";
    h += qualityPlotScript(r.frame_log ? &*r.frame_log : nullptr, r.t0_ns);
  }
  h += "</body>\n</html>\n";
  return h;
}

}  // namespace vkloc
