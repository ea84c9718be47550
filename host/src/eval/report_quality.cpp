// Per-frame quality plots of the HTML report (see report_quality.hpp).
#include "eval/report_quality.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

namespace vkloc {
namespace {

using nlohmann::json;

constexpr size_t kMaxPoints = 5000;  // per series, as the report's other plots

struct Series {
  const char* column;
  const char* label;
  const char* colour;
  bool dashed;
};

struct QualityPlot {
  const char* id;
  const char* title;
  const char* y_title;
  std::vector<Series> series;
  std::vector<const char*> needs;  // the plot is drawn when the log has one of these columns
};

const std::vector<QualityPlot>& qualityPlots() {
  static const std::vector<QualityPlot> plots{
      {"q_inliers",
       "Inlier ratio and verification score over time",
       "ratio / score",
       {{"inlier_ratio", "inlier ratio", "#2ca02c", false},
        {"chance_inlier_ratio", "chance inlier ratio", "#7f7f7f", true},
        {"verify_score", "verification score", "#1f77b4", false}},
       {"inlier_ratio", "verify_score"}},
      {"q_nis",
       "Filter innovation over time (NIS)",
       "squared Mahalanobis distance",
       {{"ekf_nis", "EKF NIS", "#9467bd", false}},
       {"ekf_nis"}},
      {"q_isigma",
       "Inertial prediction uncertainty over time",
       "1-sigma (m)",
       {{"inertial_sigma_m", "inertial 1-sigma", "#bcbd22", false}},
       {"inertial_sigma_m"}},
  };
  return plots;
}

bool hasAny(const FrameLog& log, const std::vector<const char*>& names) {
  return std::any_of(names.begin(), names.end(), [&log](const char* n) { return log.column(n) != nullptr; });
}

bool hasState(const FrameLog& log) { return !log.state.empty() && log.state.size() == log.t_ns.size(); }

std::vector<const QualityPlot*> activePlots(const FrameLog& log) {
  std::vector<const QualityPlot*> active;
  for (const QualityPlot& p : qualityPlots()) {
    if (hasAny(log, p.needs)) active.push_back(&p);
  }
  return active;
}

// Rounds for plots: 7 significant digits are more than a screen shows.
double r7(double v) {
  if (!std::isfinite(v) || v == 0.0) return v;
  const double mag = std::pow(10.0, 6 - std::floor(std::log10(std::abs(v))));
  return std::round(v * mag) / mag;
}

double seconds(int64_t t_ns, int64_t t0_ns) { return static_cast<double>(t_ns - t0_ns) * 1e-9; }

// A state name reduced to characters that need no escaping in HTML or JavaScript.
std::string safeName(const std::string& s) {
  std::string out;
  for (char c : s) {
    if ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-') out += c;
  }
  return out.empty() ? std::string("other") : out;
}

// The state as runs: a point where the state changes (and one at the last frame); y = index in
// `names` (lost, inertial, tracking, then other states in order of appearance). Exact at any
// length, unlike decimation.
json stateRuns(const FrameLog& log, int64_t t0_ns) {
  std::vector<std::string> names{"lost", "inertial", "tracking"};
  json t = json::array(), y = json::array();
  long previous = -1;
  for (size_t i = 0; i < log.state.size(); ++i) {
    const std::string name = safeName(log.state[i]);
    auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) it = names.insert(names.end(), name);
    const long k = it - names.begin();
    if (k != previous || i + 1 == log.state.size()) {
      t.push_back(r7(seconds(log.t_ns[i], t0_ns)));
      y.push_back(k);
      previous = k;
    }
  }
  return json{{"t", t}, {"y", y}, {"names", names}};
}

const char* kQualityScript = R"JS(
(function(){
const line=(label,data,color,dashed)=>({label:label,data:data,borderColor:color,backgroundColor:color,
  borderWidth:1.5,pointRadius:0,showLine:true,fill:false,spanGaps:false,borderDash:dashed?[5,4]:[]});
const opts=(yt,extra)=>Object.assign({animation:false,normalized:true,responsive:true,
  interaction:{mode:'nearest',intersect:false},plugins:{legend:{position:'top'}},
  scales:{x:{type:'linear',title:{display:true,text:'time (s)'}},y:{type:'linear',title:{display:true,text:yt}}}},
  extra||{});
const chart=(id,cfg)=>{const el=document.getElementById(id);if(el)new Chart(el,cfg);};
for(const p of Q.plots){chart(p.id,{type:'scatter',data:{datasets:p.series.map(s=>line(s.label,
  Q.t.map((t,i)=>({x:t,y:s.values[i]})),s.colour,s.dashed))},options:opts(p.y)});}
if(Q.state){const S=Q.state,cols={lost:'#d62728',inertial:'#bcbd22',tracking:'#2ca02c'};
  const col=k=>cols[S.names[k]]||'#7f7f7f';
  const o=opts('state');o.scales.y=Object.assign(o.scales.y,{min:-0.3,max:S.names.length-0.7,
    ticks:{stepSize:1,callback:v=>S.names[v]||''}});
  o.plugins.legend={display:false};
  chart('q_state',{type:'scatter',data:{datasets:[{label:'state',data:S.t.map((t,i)=>({x:t,y:S.y[i]})),
    showLine:true,stepped:'after',pointRadius:0,borderWidth:2,borderColor:'#444',fill:'origin',
    backgroundColor:'rgba(127,127,127,0.15)',
    segment:{borderColor:c=>col(c.p0.parsed.y),backgroundColor:c=>col(c.p0.parsed.y)+'33'}}]},options:o});}
})();
)JS";

}  // namespace

std::string qualityPlotDivs(const FrameLog* log) {
  if (log == nullptr || log->t_ns.empty()) return "";
  std::string h;
  auto div = [&h](const char* id, const char* title) {
    h += fmt::format("<div class=\"plot\"><h3>{}</h3><canvas id=\"{}\"></canvas></div>\n", title, id);
  };
  if (hasState(*log)) div("q_state", "Tracking state over time");
  for (const QualityPlot* p : activePlots(*log)) div(p->id, p->title);
  return h;
}

std::string qualityPlotScript(const FrameLog* log, int64_t t0_ns) {
  if (log == nullptr || log->t_ns.empty()) return "";
  const std::vector<const QualityPlot*> active = activePlots(*log);
  if (active.empty() && !hasState(*log)) return "";
  const size_t n = log->t_ns.size();
  const size_t step = std::max<size_t>(1, (n + kMaxPoints - 1) / kMaxPoints);
  std::vector<size_t> idx;
  for (size_t i = 0; i < n; i += step) idx.push_back(i);
  if (idx.back() != n - 1) idx.push_back(n - 1);
  json q;
  json t = json::array();
  for (size_t i : idx) t.push_back(r7(seconds(log->t_ns[i], t0_ns)));
  q["t"] = t;
  json plots = json::array();
  for (const QualityPlot* p : active) {
    json series = json::array();
    for (const Series& s : p->series) {
      const std::vector<double>* column = log->column(s.column);
      if (column == nullptr || column->size() != n) continue;
      json values = json::array();
      for (size_t i : idx) values.push_back(std::isfinite((*column)[i]) ? json(r7((*column)[i])) : json(nullptr));
      series.push_back({{"label", s.label}, {"colour", s.colour}, {"dashed", s.dashed}, {"values", values}});
    }
    plots.push_back({{"id", p->id}, {"y", p->y_title}, {"series", series}});
  }
  q["plots"] = plots;
  q["state"] = hasState(*log) ? stateRuns(*log, t0_ns) : json(nullptr);
  return "<script>\nconst Q=" + q.dump() + ";\n" + kQualityScript + "</script>\n";
}

}  // namespace vkloc
