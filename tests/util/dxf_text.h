// Test helper (header-only, no dxflib): builds small ASCII DXF drawings in code, so that tests
// make their own data. Numbers are written with shortest round-trip text (exact).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/text_format.h"

namespace candi::testing {

class DxfText {
 public:
  // insunits < 0 leaves $INSUNITS out.
  explicit DxfText(int insunits = 6) : insunits_(insunits) {}

  DxfText& LwPolyline(const std::string& layer, const std::vector<Eigen::Vector2d>& points,
                      const std::vector<double>& bulges = {}, bool closed = false) {
    Entity("LWPOLYLINE", layer);
    Pair(90, std::to_string(points.size()));
    Pair(70, closed ? "1" : "0");
    for (size_t k = 0; k < points.size(); ++k) {
      XY(10, points[k]);
      if (k < bulges.size() && bulges[k] != 0) Pair(42, FormatDouble(bulges[k]));
    }
    return *this;
  }
  DxfText& Polyline(const std::string& layer, const std::vector<Eigen::Vector2d>& points,
                    bool closed = false, int extra_flags = 0) {
    Entity("POLYLINE", layer);
    Pair(66, "1");
    XY(10, Eigen::Vector2d::Zero());
    Pair(70, std::to_string((closed ? 1 : 0) | extra_flags));
    for (const Eigen::Vector2d& p : points) {
      Entity("VERTEX", layer);
      XY(10, p);
    }
    Entity("SEQEND", layer);
    return *this;
  }
  DxfText& Line(const std::string& layer, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    Entity("LINE", layer);
    XY(10, a);
    XY(11, b);
    return *this;
  }
  // Lines joining consecutive points, written in the given order and direction.
  DxfText& Lines(const std::string& layer, const std::vector<Eigen::Vector2d>& points) {
    for (size_t k = 0; k + 1 < points.size(); ++k) Line(layer, points[k], points[k + 1]);
    return *this;
  }
  DxfText& Spline(const std::string& layer, const std::vector<Eigen::Vector2d>& fit,
                  const std::vector<Eigen::Vector2d>& control = {}) {
    Entity("SPLINE", layer);
    Pair(70, "8");
    Pair(71, "3");
    Pair(73, std::to_string(control.size()));
    Pair(74, std::to_string(fit.size()));
    for (const Eigen::Vector2d& p : control) XY(10, p);
    for (const Eigen::Vector2d& p : fit) XY(11, p);
    return *this;
  }
  DxfText& Circle(const std::string& layer, const Eigen::Vector2d& c, double r) {
    Entity("CIRCLE", layer);
    XY(10, c);
    Pair(40, FormatDouble(r));
    return *this;
  }

  std::string str() const {
    std::string header = "0\nSECTION\n2\nHEADER\n9\n$ACADVER\n1\nAC1015\n";
    if (insunits_ >= 0) header += "9\n$INSUNITS\n70\n" + std::to_string(insunits_) + "\n";
    return header + "0\nENDSEC\n0\nSECTION\n2\nENTITIES\n" + body_ + "0\nENDSEC\n0\nEOF\n";
  }

 private:
  void Pair(int code, const std::string& value) {
    body_ += std::to_string(code) + "\n" + value + "\n";
  }
  void Entity(const std::string& type, const std::string& layer) {
    Pair(0, type);
    Pair(8, layer);
  }
  void XY(int code, const Eigen::Vector2d& p) {
    Pair(code, FormatDouble(p.x()));
    Pair(code + 10, FormatDouble(p.y()));
    Pair(code + 20, "0");
  }

  int insunits_;
  std::string body_;
};

}  // namespace candi::testing
