// The only C++ in hrtao: reads STEP/IGES through OpenCASCADE's XCAF readers, walks the product structure,
// tessellates each unique part once and hands everything to Rust through the callbacks of bridge.h.
// Every entry point catches all C++ exceptions and turns them into an error message.
#include "bridge.h"

#include <BRepBndLib.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <IGESCAFControl_Writer.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Message_ProgressIndicator.hxx>
#include <Message_ProgressScope.hxx>
#include <NCollection_DataMap.hxx>
#include <NCollection_Map.hxx>
#include <TDF_LabelMapHasher.hxx>
#include <Poly_Triangulation.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_ShapeMapHasher.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Face.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XSControl_WorkSession.hxx>
#include <gp_Trsf.hxx>

#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace {

// Deepest product structure walked (a deeper one is an error, as is an assembly containing itself).
const int kMaxDepth = 256;

struct Failure {
  std::string message;
};
struct Stopped {};

void copy_error(const std::string& m, char* err, size_t len) {
  if (!err || len == 0) return;
  size_t n = m.size() < len - 1 ? m.size() : len - 1;
  std::memcpy(err, m.data(), n);
  err[n] = 0;
}

// OCCT's progress indicator, forwarding to the Rust callback; its answer is OCCT's user break.
class Progress : public Message_ProgressIndicator {
 public:
  explicit Progress(const hr_callbacks* cb) : cb_(cb) {}
  void set_stage(const char* s) { stage_ = s; }
  Standard_Boolean UserBreak() override { return stop_; }
  void Show(const Message_ProgressScope&, const Standard_Boolean) override { report(GetPosition()); }
  void report(double f) {
    if (cb_->progress && cb_->progress(cb_->ctx, f, stage_)) stop_ = true;
  }
  bool stopped() const { return stop_; }

 private:
  const hr_callbacks* cb_;
  const char* stage_ = "read";
  bool stop_ = false;
};

std::string label_name(const TDF_Label& l) {
  Handle(TDataStd_Name) n;
  if (l.FindAttribute(TDataStd_Name::GetID(), n)) {
    TCollection_AsciiString a(n->Get());
    return std::string(a.ToCString());
  }
  return std::string();
}

bool label_color(const Handle(XCAFDoc_ColorTool)& ct, const TDF_Label& l, std::array<float, 4>& out) {
  Quantity_ColorRGBA c;
  if (ct->GetColor(l, XCAFDoc_ColorSurf, c) || ct->GetColor(l, XCAFDoc_ColorGen, c)) {
    out = {(float)c.GetRGB().Red(), (float)c.GetRGB().Green(), (float)c.GetRGB().Blue(), c.Alpha()};
    return true;
  }
  return false;
}

struct Walker {
  const hr_callbacks* cb;
  Progress* progress;
  hr_tessellation tess;
  Handle(XCAFDoc_ShapeTool) st;
  Handle(XCAFDoc_ColorTool) ct;
  NCollection_DataMap<TDF_Label, int32_t, TDF_LabelMapHasher> parts;  // part label -> part id (-1: no triangles)
  NCollection_Map<TDF_Label, TDF_LabelMapHasher> on_path;
  int32_t next_part = 0;
  size_t parts_total = 1, parts_done = 0;

  // Tessellates a part once and sends its primitives, one per colour; returns the part id or -1.
  int32_t part(const TDF_Label& label, const std::string& name) {
    if (const int32_t* known = parts.Seek(label)) return *known;
    TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
    int32_t id = -1;
    if (!shape.IsNull()) id = tessellate(label, shape, name);
    parts.Bind(label, id);
    parts_done++;
    progress->set_stage("tessellate");
    progress->report((double)parts_done / (double)parts_total);
    if (progress->stopped()) throw Stopped{};
    return id;
  }

  int32_t tessellate(const TDF_Label& label, const TopoDS_Shape& shape, const std::string& name) {
    Bnd_Box box;
    BRepBndLib::Add(shape, box);
    if (box.IsVoid()) return -1;
    double diag = std::sqrt(box.SquareExtent());
    double lin = tess.relative > 0 ? tess.relative * diag : tess.absolute;
    if (!(lin > 0) || !std::isfinite(lin)) lin = 1e-3 * (diag > 0 ? diag : 1.0);
    // In parallel over the part's faces (OSD_Parallel's thread pool): a part of many faces meshes on every core.
    BRepMesh_IncrementalMesh mesher(shape, lin, Standard_False, tess.angular, Standard_True);
    if (!mesher.IsDone()) return -1;

    // Colours set on the part's sub-shapes (faces, shells, solids) win over the part's own colour.
    NCollection_DataMap<TopoDS_Shape, std::array<float, 4>, TopTools_ShapeMapHasher> face_colors;
    TDF_LabelSequence subs;
    XCAFDoc_ShapeTool::GetSubShapes(label, subs);
    for (Standard_Integer i = 1; i <= subs.Length(); i++) {
      std::array<float, 4> c;
      if (!label_color(ct, subs.Value(i), c)) continue;
      TopoDS_Shape sub = XCAFDoc_ShapeTool::GetShape(subs.Value(i));
      for (TopExp_Explorer f(sub, TopAbs_FACE); f.More(); f.Next()) face_colors.Bind(f.Current(), c);
    }
    std::array<float, 4> own;
    bool has_own = label_color(ct, label, own);

    struct Prim {
      std::vector<float> pos;
      std::vector<uint32_t> idx;
      std::array<float, 4> rgba;
      bool colored, face;
    };
    std::map<std::array<float, 4>, Prim> by_color;  // key {-1,..} for "no colour"
    for (TopExp_Explorer f(shape, TopAbs_FACE); f.More(); f.Next()) {
      const TopoDS_Face& face = TopoDS::Face(f.Current());
      TopLoc_Location loc;
      Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(face, loc);
      if (tri.IsNull() || tri->NbTriangles() == 0) continue;
      std::array<float, 4> key = {-1, -1, -1, -1};
      bool face_colored = false;
      if (const std::array<float, 4>* c = face_colors.Seek(face)) {
        key = *c;
        face_colored = true;
      } else if (has_own) {
        key = own;
      }
      Prim& p = by_color[key];
      p.rgba = key;
      p.colored = key[0] >= 0;
      p.face = p.face || face_colored;
      gp_Trsf t = loc.Transformation();
      uint32_t base = (uint32_t)(p.pos.size() / 3);
      for (Standard_Integer i = 1; i <= tri->NbNodes(); i++) {
        gp_Pnt q = tri->Node(i).Transformed(t);
        p.pos.push_back((float)q.X());
        p.pos.push_back((float)q.Y());
        p.pos.push_back((float)q.Z());
      }
      bool reversed = face.Orientation() == TopAbs_REVERSED;
      for (Standard_Integer i = 1; i <= tri->NbTriangles(); i++) {
        Standard_Integer a, b, c;
        tri->Triangle(i).Get(a, b, c);
        if (reversed) std::swap(b, c);
        p.idx.push_back(base + a - 1);
        p.idx.push_back(base + b - 1);
        p.idx.push_back(base + c - 1);
      }
    }
    if (by_color.empty()) return -1;
    int32_t id = next_part++;
    cb->part(cb->ctx, id, name.c_str());
    for (auto& kv : by_color) {
      Prim& p = kv.second;
      cb->primitive(cb->ctx, id, p.pos.data(), p.pos.size() / 3, p.idx.data(), p.idx.size(),
                    p.colored ? p.rgba.data() : nullptr, p.face ? 1 : 0);
    }
    return id;
  }

  // Walks one label (a free shape or a component) under `parent` placed at `world`.
  void walk(const TDF_Label& label, int32_t parent, const gp_Trsf& parent_world, const std::array<float, 4>* inherited,
            bool parent_visible, int depth) {
    if (depth > kMaxDepth) throw Failure{"the product structure is deeper than 256 levels"};
    TDF_Label def = label;
    gp_Trsf world = parent_world;
    if (XCAFDoc_ShapeTool::IsReference(label)) {
      if (!XCAFDoc_ShapeTool::GetReferredShape(label, def)) return;
      world = parent_world * XCAFDoc_ShapeTool::GetLocation(label).Transformation();
    }
    std::string name = label_name(label);
    if (name.empty()) name = label_name(def);
    if (on_path.Contains(def)) throw Failure{"the assembly \"" + name + "\" contains itself"};
    std::array<float, 4> own;
    const std::array<float, 4>* color = inherited;
    std::array<float, 4> here;
    if (label != def && label_color(ct, label, own)) {
      here = own;
      color = &here;
    }
    bool visible = parent_visible && ct->IsVisible(label) && ct->IsVisible(def);
    double m[16];
    for (int c = 0; c < 4; c++)
      for (int r = 0; r < 4; r++) m[c * 4 + r] = (r == 3) ? (c == 3 ? 1.0 : 0.0) : (c == 3 ? world.Value(r + 1, 4) : world.Value(r + 1, c + 1));
    if (XCAFDoc_ShapeTool::IsAssembly(def)) {
      // An assembly's own colour applies to what it contains unless they set theirs.
      std::array<float, 4> def_color;
      if (!color && label_color(ct, def, def_color)) {
        here = def_color;
        color = &here;
      }
      int32_t node = cb->node(cb->ctx, parent, name.c_str(), -1, m, color ? color->data() : nullptr, visible);
      on_path.Add(def);
      TDF_LabelSequence comps;
      XCAFDoc_ShapeTool::GetComponents(def, comps, Standard_False);
      for (Standard_Integer i = 1; i <= comps.Length(); i++)
        walk(comps.Value(i), node, world, color, visible, depth + 1);
      on_path.Remove(def);
    } else {
      int32_t id = part(def, label_name(def).empty() ? name : label_name(def));
      cb->node(cb->ctx, parent, name.c_str(), id, m, color ? color->data() : nullptr, visible);
    }
  }
};

// OCCT's messages (transfer statistics) go to stdout by default: keep them out of the caller's output.
void quiet() {
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
}

int read_impl(const char* path, int32_t format, const hr_tessellation* tess, const hr_callbacks* cb,
              hr_units* units) {
  quiet();
  Handle(Progress) progress = new Progress(cb);
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  struct Closer {
    Handle(XCAFApp_Application) app;
    Handle(TDocStd_Document) doc;
    ~Closer() {
      if (!doc.IsNull() && doc->IsOpened()) app->Close(doc);
    }
  } closer{app, doc};
  units->file_m = 0;
  // Each stage announces its start (fraction 0): the loader logs where the time goes.
  progress->set_stage("read");
  progress->report(0);
  if (progress->stopped()) throw Stopped{};
  if (format == 0) {
    STEPCAFControl_Reader reader;
    reader.SetColorMode(true);
    reader.SetNameMode(true);
    reader.SetLayerMode(false);
    reader.SetPropsMode(false);
    IFSelect_ReturnStatus s = reader.ReadFile(path);
    if (s != IFSelect_RetDone) throw Failure{"not a readable STEP file (OpenCASCADE could not parse it)"};
    TColStd_SequenceOfAsciiString lengths, angles, solids;
    reader.ChangeReader().FileUnits(lengths, angles, solids);
    if (lengths.Length() > 0) {
      TCollection_AsciiString u = lengths.Value(1);
      u.LowerCase();
      if (u.Search("milli") >= 0) units->file_m = 1e-3;
      else if (u.Search("centi") >= 0) units->file_m = 1e-2;
      else if (u.Search("micro") >= 0) units->file_m = 1e-6;
      else if (u.Search("kilo") >= 0) units->file_m = 1e3;
      else if (u.Search("inch") >= 0) units->file_m = 0.0254;
      else if (u.Search("foot") >= 0 || u.Search("feet") >= 0) units->file_m = 0.3048;
      else if (u.Search("metre") >= 0 || u.Search("meter") >= 0) units->file_m = 1.0;
    }
    progress->set_stage("transfer");
    progress->report(0);
    if (!reader.Transfer(doc, progress->Start())) {
      if (progress->stopped()) throw Stopped{};
      throw Failure{"OpenCASCADE found no shape to transfer in the STEP file"};
    }
  } else {
    IGESControl_Controller::Init();
    IGESCAFControl_Reader reader;
    reader.SetColorMode(true);
    reader.SetNameMode(true);
    reader.SetLayerMode(false);
    IFSelect_ReturnStatus s = reader.ReadFile(path);
    if (s != IFSelect_RetDone) throw Failure{"not a readable IGES file (OpenCASCADE could not parse it)"};
    Handle(IGESData_IGESModel) model = reader.IGESModel();
    if (!model.IsNull()) {
      // IGES unit flags (global section, parameter 14).
      static const double flag_m[] = {0, 0.0254, 1e-3, 0, 0.3048, 1609.344, 1.0, 1e3, 2.54e-5, 1e-6, 1e-2, 2.54e-8};
      Standard_Integer f = model->GlobalSection().UnitFlag();
      if (f >= 1 && f <= 11) units->file_m = flag_m[f];
    }
    progress->set_stage("transfer");
    progress->report(0);
    if (!reader.Transfer(doc, progress->Start())) {
      if (progress->stopped()) throw Stopped{};
      throw Failure{"OpenCASCADE found no shape to transfer in the IGES file"};
    }
  }
  if (progress->stopped()) throw Stopped{};
  double model_m = 1e-3;
  if (!XCAFDoc_DocumentTool::GetLengthUnit(doc, model_m) || !(model_m > 0)) model_m = 1e-3;
  units->model_m = model_m;

  Walker w;
  w.cb = cb;
  w.progress = progress.get();
  w.tess = *tess;
  w.st = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  w.ct = XCAFDoc_DocumentTool::ColorTool(doc->Main());
  TDF_LabelSequence shapes, roots;
  w.st->GetShapes(shapes);
  w.parts_total = shapes.Length() > 0 ? (size_t)shapes.Length() : 1;
  w.st->GetFreeShapes(roots);
  if (roots.Length() == 0) throw Failure{"the file holds no shape"};
  progress->set_stage("tessellate");
  progress->report(0);
  if (progress->stopped()) throw Stopped{};
  for (Standard_Integer i = 1; i <= roots.Length(); i++) w.walk(roots.Value(i), -1, gp_Trsf(), nullptr, true, 0);
  return 0;
}

TopoDS_Shape bolt() {
  BRep_Builder b;
  TopoDS_Compound c;
  b.MakeCompound(c);
  b.Add(c, BRepPrimAPI_MakeCylinder(3.0, 20.0).Shape());
  gp_Trsf up;
  up.SetTranslation(gp_Vec(-5, -5, 20));
  b.Add(c, BRepPrimAPI_MakeBox(10, 10, 5).Shape().Moved(TopLoc_Location(up)));
  return c;
}

int write_impl(const char* path, int32_t format, int32_t kind, int32_t count) {
  quiet();
  // Without p-curves a box takes about a third of the entities.
  Interface_Static::SetIVal("write.surfacecurve.mode", kind == 3 ? 0 : 1);
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  Handle(XCAFDoc_ShapeTool) st = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  Handle(XCAFDoc_ColorTool) ct = XCAFDoc_DocumentTool::ColorTool(doc->Main());
  auto at = [](double x, double y, double z) {
    gp_Trsf t;
    t.SetTranslation(gp_Vec(x, y, z));
    return TopLoc_Location(t);
  };
  if (kind == 0) {
    for (int i = 0; i < 3; i++) {
      TDF_Label l = st->AddShape(BRepPrimAPI_MakeBox(gp_Pnt(30.0 * i, 0, 0), 10 + 5.0 * i, 10, 10).Shape(), false);
      TDataStd_Name::Set(l, TCollection_ExtendedString(("box" + std::to_string(i + 1)).c_str()));
    }
  } else if (kind == 1) {
    TDF_Label asm_ = st->NewShape();
    TDataStd_Name::Set(asm_, "bolt_pattern");
    TDF_Label plate = st->AddShape(BRepPrimAPI_MakeBox(gp_Pnt(-60, -60, -10), 120, 120, 10).Shape(), false);
    TDataStd_Name::Set(plate, "plate");
    TDF_Label b = st->AddShape(bolt(), false);
    TDataStd_Name::Set(b, "bolt");
    st->AddComponent(asm_, plate, TopLoc_Location());
    for (int i = 0; i < count; i++) {
      double a = 2 * M_PI * i / count;
      TDF_Label c = st->AddComponent(asm_, b, at(40 * std::cos(a), 40 * std::sin(a), 0));
      TDataStd_Name::Set(c, TCollection_ExtendedString(("bolt" + std::to_string(i + 1)).c_str()));
    }
    st->UpdateAssemblies();
  } else if (kind == 2) {
    TDF_Label asm_ = st->NewShape();
    TDataStd_Name::Set(asm_, "coloured");
    TopoDS_Shape red_box = BRepPrimAPI_MakeBox(10, 10, 10).Shape();
    TDF_Label red = st->AddShape(red_box, false);
    TDataStd_Name::Set(red, "red_part");
    ct->SetColor(red, Quantity_Color(1, 0, 0, Quantity_TOC_RGB), XCAFDoc_ColorSurf);
    TopoDS_Shape faced = BRepPrimAPI_MakeBox(10, 10, 10).Shape();
    TDF_Label face_part = st->AddShape(faced, false);
    TDataStd_Name::Set(face_part, "blue_top_part");
    TopExp_Explorer f(faced, TopAbs_FACE);
    TDF_Label face_label = st->AddSubShape(face_part, f.Current());
    ct->SetColor(face_label, Quantity_Color(0, 0, 1, Quantity_TOC_RGB), XCAFDoc_ColorSurf);
    st->AddComponent(asm_, red, at(0, 0, 0));
    TDF_Label green = st->AddComponent(asm_, red, at(20, 0, 0));
    TDataStd_Name::Set(green, "green_occurrence");
    ct->SetColor(green, Quantity_Color(0, 1, 0, Quantity_TOC_RGB), XCAFDoc_ColorSurf);
    st->AddComponent(asm_, face_part, at(40, 0, 0));
    TDF_Label hidden = st->AddComponent(asm_, red, at(60, 0, 0));
    TDataStd_Name::Set(hidden, "hidden_occurrence");
    ct->SetColor(hidden, Quantity_Color(1, 1, 0, Quantity_TOC_RGB), XCAFDoc_ColorSurf);
    ct->SetVisibility(hidden, Standard_False);
    st->UpdateAssemblies();
  } else if (kind == 3) {
    BRep_Builder b;
    TopoDS_Compound c;
    b.MakeCompound(c);
    int side = (int)std::ceil(std::sqrt((double)count));
    for (int i = 0; i < count; i++)
      b.Add(c, BRepPrimAPI_MakeBox(gp_Pnt(2.0 * (i % side), 2.0 * (i / side), 0), 1, 1, 1).Shape());
    st->AddShape(c, false);
  } else {
    throw Failure{"unknown test model kind"};
  }
  bool ok;
  if (format == 0) {
    STEPCAFControl_Writer w;
    ok = w.Transfer(doc, STEPControl_AsIs) && w.Write(path) == IFSelect_RetDone;
  } else {
    IGESControl_Controller::Init();
    IGESCAFControl_Writer w;
    ok = w.Transfer(doc) && w.Write(path);
  }
  app->Close(doc);
  if (!ok) throw Failure{std::string("OpenCASCADE could not write ") + path};
  return 0;
}

}  // namespace

extern "C" int hr_read(const char* path, int32_t format, const hr_tessellation* tess, const hr_callbacks* cb,
                       hr_units* units, char* err, size_t err_len) {
  try {
    return read_impl(path, format, tess, cb, units);
  } catch (const Stopped&) {
    return 2;
  } catch (const Failure& f) {
    copy_error(f.message, err, err_len);
  } catch (const Standard_Failure& e) {
    copy_error(std::string("OpenCASCADE failed: ") + e.DynamicType()->Name() + ": " + e.GetMessageString(), err,
               err_len);
  } catch (const std::exception& e) {
    copy_error(std::string("C++ exception: ") + e.what(), err, err_len);
  } catch (...) {
    copy_error("unknown C++ exception inside OpenCASCADE", err, err_len);
  }
  return 1;
}

extern "C" int hr_write_test(const char* path, int32_t format, int32_t kind, int32_t count, char* err,
                             size_t err_len) {
  try {
    return write_impl(path, format, kind, count);
  } catch (const Failure& f) {
    copy_error(f.message, err, err_len);
  } catch (const Standard_Failure& e) {
    copy_error(std::string("OpenCASCADE failed: ") + e.GetMessageString(), err, err_len);
  } catch (...) {
    copy_error("unknown C++ exception inside OpenCASCADE", err, err_len);
  }
  return 1;
}
