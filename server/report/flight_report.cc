#include "server/report/flight_report.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "server/report/chart.h"
#include "server/report/top_down.h"

namespace enavi::report {

std::string TimeSeriesCsv(const api::TimeSeries& s) {
  // wind_speed and odometry_error only when the episode has them (api::TimeSeries).
  const bool wind = !s.wind_speed.empty(), odometry = !s.odometry_error.empty();
  std::string out = "t,x,y,z,vx,vy,vz,speed,eci,f_per,f_col,f_dif,res,utilisation,";
  out += std::string(wind ? "wind_speed," : "") + (odometry ? "odometry_error," : "") + "events\n";
  char line[512];
  for (std::size_t i = 0; i < s.size(); ++i) {
    const api::Vec3& p = s.position[i];
    const api::Vec3& v = s.velocity[i];
    const double speed = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    std::snprintf(line, sizeof line, "%.3f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.2f,%.2f,%.2f,%.3f,%.2f,",
                  s.t[i], p[0], p[1], p[2], v[0], v[1], v[2], speed, s.eci[i], s.f_per[i], s.f_col[i], s.f_dif[i],
                  s.res[i], s.utilisation[i]);
    out += line;
    if (wind) {
      std::snprintf(line, sizeof line, "%.3f,", s.wind_speed[i]);
      out += line;
    }
    if (odometry) {
      std::snprintf(line, sizeof line, "%.4f,", s.odometry_error[i]);
      out += line;
    }
    out += i < s.events.size() ? s.events[i] : "";
    out += '\n';
  }
  return out;
}

namespace {

std::string Caption(const api::EpisodeResult& result) {
  return result.spec.method + " on " + result.spec.board + ", " + result.scenario + " seed " +
         std::to_string(result.spec.seed) + ": " + result.end_reason;
}

// Bird's-eye view: the flown path coloured by eci (the paper's Fig. of trajectories).
void DrawFlight(const api::EpisodeResult& result, TopDownView* top) {
  std::vector<Eigen::Vector2d> xy;
  for (const auto& p : result.series.position) xy.emplace_back(p[0], p[1]);
  // Movers where they were when the flight ended (at a collision: what it hit and where).
  top->DrawMoversAt(result.sim_time_s, "movers at the end");
  if (xy.size() >= 2) top->DrawPath(xy, result.series.eci, 0.0, 1.0, "eci");
  if (result.collision_point)
    top->DrawMarker({(*result.collision_point)[0], (*result.collision_point)[1]}, Rgb{0.85, 0.1, 0.1},
                    result.collided_with.rfind("mover:", 0) == 0 ? "collision with " + result.collided_with.substr(6)
                                                                 : "collision");
}

}  // namespace

std::vector<std::uint8_t> FlightTopDownPng(const api::EpisodeResult& result, const worlds::World& world,
                                           int width) {
  TopDownOptions options;
  options.title = Caption(result);
  options.width = width;
  TopDownView top(world, options);
  DrawFlight(result, &top);
  return top.canvas().PngBytes();
}

void WriteFlightPlots(const api::EpisodeResult& result, const worlds::World& world, const std::string& dir) {
  const api::TimeSeries& s = result.series;
  const std::filesystem::path out(dir);
  const std::string what = Caption(result);

  TopDownOptions top_options;
  top_options.title = what;
  TopDownView top(world, top_options);
  DrawFlight(result, &top);
  top.SavePng((out / "flight_topdown.png").string());

  // Speed and navigation workload over time (the paper's velocity and utilisation figures).
  std::vector<double> speed;
  for (const auto& v : s.velocity) speed.push_back(std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
  ChartStack motion(what);
  motion.AddPanel("speed", "m/s").AddSeries("|v|", s.t, speed);
  motion.AddPanel("navigation CPU utilisation (% of one core)", "%").AddSeries("nav tasks", s.t, s.utilisation);
  if (!s.wind_speed.empty()) motion.AddPanel("wind at the vehicle", "m/s").AddSeries("|air|", s.t, s.wind_speed);
  if (!s.odometry_error.empty())
    motion.AddPanel("odometry error (estimate - truth)", "m").AddSeries("|dp|", s.t, s.odometry_error);
  motion.SavePng((out / "speed.png").string());

  // Adaptation: eci with the task frequencies and map resolution (paper Fig. "eci, perception,
  // planning periods, resolution").
  ChartStack adapt(what);
  adapt.AddPanel("eci", "eci").AddSeries("eci", s.t, s.eci).SetYRange(0.0, 1.0);
  Chart& rates = adapt.AddPanel("task frequencies", "Hz");
  for (const auto& [name, values] : {std::pair{"f_per", &s.f_per}, {"f_col", &s.f_col}, {"f_dif", &s.f_dif}}) {
    Series series{.name = name, .x = s.t, .y = *values, .step = true};
    rates.AddSeries(series);
  }
  Series res{.name = "res", .x = s.t, .y = s.res, .step = true};
  adapt.AddPanel("map resolution", "m").AddSeries(res);
  adapt.SavePng((out / "adaptation.png").string());
}

void WriteEciFramesPlot(const api::EpisodeResult& result, const EciFrameSeries& f, const std::string& path) {
  ChartStack chart(Caption(result) + ": eci per frame");
  chart.AddPanel("eci of every depth frame", "eci").AddSeries("eci", f.t, f.eci).SetYRange(0.0, 1.0);
  chart.AddPanel("d0: nearest return in view (layer width 2 d0)", "m").AddSeries("d0", f.t, f.d0);
  chart.AddPanel("camera pitch (+: nose up, the ground leaves the view)", "deg")
      .AddSeries("pitch", f.t, f.camera_pitch_deg);
  chart.SavePng(path);
}

}  // namespace enavi::report
