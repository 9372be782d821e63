#include "io/crs.h"

#include <proj.h>

#include <cmath>
#include <limits>

#include "core/check.h"

namespace candi::io {

namespace {

// One PROJ context for the life of a call (contexts are not thread-safe; creating one is cheap
// next to the database lookups that follow).
class Context {
 public:
  Context() : ctx_(proj_context_create()) {
    CANDI_CHECK(ctx_ != nullptr) << "proj_context_create failed";
    proj_log_level(ctx_, PJ_LOG_NONE);
  }
  ~Context() { proj_context_destroy(ctx_); }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  PJ_CONTEXT* get() const { return ctx_; }
  std::string LastError() const {
    const int e = proj_context_errno(ctx_);
    const char* s = e != 0 ? proj_context_errno_string(ctx_, e) : nullptr;
    return s ? s : "unknown reason";
  }

 private:
  PJ_CONTEXT* ctx_;
};

struct PjDeleter {
  void operator()(PJ* p) const { proj_destroy(p); }
};
using PjPtr = std::unique_ptr<PJ, PjDeleter>;

std::string Shortened(const std::string& s) {
  std::string one_line;
  for (char c : s) one_line += (c == '\n' || c == '\r') ? ' ' : c;
  return one_line.size() <= 60 ? one_line : one_line.substr(0, 57) + "...";
}

PjPtr CreateCrs(const Context& ctx, const std::string& definition, const std::string& where) {
  if (definition.empty()) throw InputError(where, "", "empty CRS");
  PjPtr pj(proj_create(ctx.get(), definition.c_str()));
  if (!pj) {
    throw InputError(where, "", "PROJ cannot read the CRS '" + Shortened(definition) + "': " + ctx.LastError());
  }
  if (!proj_is_crs(pj.get())) {
    throw InputError(where, "", "'" + Shortened(definition) + "' is not a coordinate reference system");
  }
  return pj;
}

std::string TypeName(PJ_TYPE type) {
  switch (type) {
    case PJ_TYPE_GEOGRAPHIC_2D_CRS: return "geographic 2D";
    case PJ_TYPE_GEOGRAPHIC_3D_CRS: return "geographic 3D";
    case PJ_TYPE_GEOCENTRIC_CRS: return "geocentric";
    case PJ_TYPE_PROJECTED_CRS: return "projected";
    case PJ_TYPE_VERTICAL_CRS: return "vertical";
    case PJ_TYPE_COMPOUND_CRS: return "compound";
    case PJ_TYPE_ENGINEERING_CRS: return "engineering";
    case PJ_TYPE_BOUND_CRS: return "bound";
    default: return "other";
  }
}

std::string IdOf(const Context& ctx, PJ* pj) {
  const char* auth = proj_get_id_auth_name(pj, 0);
  const char* code = proj_get_id_code(pj, 0);
  if (auth && code) return std::string(auth) + ":" + code;
  int* confidence = nullptr;
  PJ_OBJ_LIST* list = proj_identify(ctx.get(), pj, "EPSG", nullptr, &confidence);
  std::string id;
  if (list && proj_list_get_count(list) > 0 && confidence && confidence[0] >= 70) {
    PjPtr best(proj_list_get(ctx.get(), list, 0));
    const char* c = best ? proj_get_id_code(best.get(), 0) : nullptr;
    if (c) id = std::string("EPSG:") + c;
  }
  proj_int_list_destroy(confidence);
  proj_list_destroy(list);
  return id;
}

}  // namespace

CrsDescription DescribeCrs(const std::string& definition, const std::string& where) {
  const Context ctx;
  const PjPtr pj = CreateCrs(ctx, definition, where);
  CrsDescription d;
  const char* name = proj_get_name(pj.get());
  d.name = name ? name : "";
  d.id = IdOf(ctx, pj.get());
  const PJ_TYPE type = proj_get_type(pj.get());
  d.type = TypeName(type);
  d.geographic = type == PJ_TYPE_GEOGRAPHIC_2D_CRS || type == PJ_TYPE_GEOGRAPHIC_3D_CRS;
  return d;
}

std::string CrsLabel(const std::string& definition) {
  try {
    const CrsDescription d = DescribeCrs(definition, "CRS");
    return d.id.empty() ? d.name : d.name + " (" + d.id + ")";
  } catch (const InputError&) {
    return Shortened(definition);
  }
}

bool SameCrs(const std::string& a, const std::string& b) {
  if (a == b) return true;
  const Context ctx;
  PjPtr pa(proj_create(ctx.get(), a.c_str())), pb(proj_create(ctx.get(), b.c_str()));
  if (!pa || !pb) return false;
  return proj_is_equivalent_to_with_ctx(ctx.get(), pa.get(), pb.get(),
                                        PJ_COMP_EQUIVALENT_EXCEPT_AXIS_ORDER_GEOGCRS) != 0;
}

std::string CrsAsWkt1(const std::string& definition, const std::string& where) {
  const Context ctx;
  const PjPtr pj = CreateCrs(ctx, definition, where);
  const char* const one_line[] = {"MULTILINE=NO", nullptr};
  const char* wkt = proj_as_wkt(ctx.get(), pj.get(), PJ_WKT1_GDAL, one_line);
  if (wkt) return wkt;
  const char* wkt2 = proj_as_wkt(ctx.get(), pj.get(), PJ_WKT2_2019, one_line);
  if (wkt2) return wkt2;
  throw InputError(where, "", "PROJ cannot write the CRS '" + Shortened(definition) + "' as WKT");
}

struct CrsTransform::Impl {
  Context ctx;
  PjPtr op;
};

CrsTransform::CrsTransform(const std::string& from, const std::string& to, const std::string& where)
    : impl_(std::make_unique<Impl>()) {
  PJ_CONTEXT* ctx = impl_->ctx.get();
  const PjPtr a = CreateCrs(impl_->ctx, from, where), b = CreateCrs(impl_->ctx, to, where);
  PjPtr op(proj_create_crs_to_crs_from_pj(ctx, a.get(), b.get(), nullptr, nullptr));
  if (!op) {
    throw InputError(where, "", "PROJ finds no transformation from " + CrsLabel(from) + " to " +
                                    CrsLabel(to) + ": " + impl_->ctx.LastError());
  }
  impl_->op.reset(proj_normalize_for_visualization(ctx, op.get()));
  if (!impl_->op) {
    throw InputError(where, "", "PROJ cannot normalise the transformation from " + CrsLabel(from) +
                                    " to " + CrsLabel(to) + ": " + impl_->ctx.LastError());
  }
  // Which of the candidate operations PROJ picks depends on the point: describe the one it picks
  // for the centre of the source's area of use (Apply refreshes it).
  double west, south, east, north;
  if (proj_get_area_of_use(ctx, a.get(), &west, &south, &east, &north, nullptr) && west <= east) {
    const PjPtr geographic(proj_crs_get_geodetic_crs(ctx, a.get()));
    PjPtr to_source(geographic ? proj_create_crs_to_crs_from_pj(ctx, geographic.get(), a.get(), nullptr, nullptr) : nullptr);
    if (to_source) {
      PjPtr normalized(proj_normalize_for_visualization(ctx, to_source.get()));
      PJ_COORD centre = proj_coord((west + east) / 2, (south + north) / 2, 0, 0);
      if (normalized) centre = proj_trans(normalized.get(), PJ_FWD, centre);
      proj_trans(impl_->op.get(), PJ_FWD, centre);
    }
  }
  DescribeLastOperation();
}

void CrsTransform::DescribeLastOperation() const {
  PjPtr last(proj_trans_get_last_used_operation(impl_->op.get()));
  PJ* op = last ? last.get() : impl_->op.get();
  const PJ_PROJ_INFO info = proj_pj_info(op);
  operation_ = info.description ? info.description : "";
  accuracy_ = last ? proj_coordoperation_get_accuracy(impl_->ctx.get(), op) : -1;
  if (!last) operation_ = "chosen by PROJ for each point among " + operation_;
  if (operation_.find("unavailable until") != std::string::npos) operation_ = "chosen by PROJ for each point";
}

CrsTransform::~CrsTransform() = default;

size_t CrsTransform::Apply(std::vector<Eigen::Vector3d>* points) const {
  if (points->empty()) return 0;
  double* data = points->front().data();
  const size_t stride = sizeof(Eigen::Vector3d);
  // proj_trans_generic takes counts as size_t; a failed point gets HUGE_VAL.
  proj_errno_reset(impl_->op.get());
  proj_trans_generic(impl_->op.get(), PJ_FWD, data, stride, points->size(), data + 1, stride, points->size(),
                     data + 2, stride, points->size(), nullptr, 0, 0);
  size_t failed = 0;
  for (Eigen::Vector3d& p : *points) {
    if (!p.allFinite() || std::abs(p.x()) == HUGE_VAL || std::abs(p.y()) == HUGE_VAL) {
      p.setConstant(std::numeric_limits<double>::quiet_NaN());
      ++failed;
    }
  }
  DescribeLastOperation();
  return failed;
}

Eigen::Vector3d CrsTransform::Apply(const Eigen::Vector3d& p) const {
  std::vector<Eigen::Vector3d> one = {p};
  Apply(&one);
  return one[0];
}

}  // namespace candi::io
