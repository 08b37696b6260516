// The only C++ in hrtao: reads STEP/IGES through OpenCASCADE's XCAF readers (IGES with its subfigures put into the
// document by IgesDoc, below), walks the product structure, tessellates each unique part once and hands everything
// to Rust through the callbacks of bridge.h.
// Every entry point catches all C++ exceptions and turns them into an error message.
#include "bridge.h"

#include <BRepBndLib.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepToIGES_BREntity.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GeomLib.hxx>
#include <Geom_Surface.hxx>
#include <Precision.hxx>
#include <Bnd_Box.hxx>
#include <IGESBasic_Group.hxx>
#include <IGESBasic_Name.hxx>
#include <IGESBasic_SingularSubfigure.hxx>
#include <IGESBasic_SubfigureDef.hxx>
#include <IGESCAFControl.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <IGESCAFControl_Writer.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESData_ColorEntity.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_HArray1OfIGESEntity.hxx>
#include <IGESData_IGESModel.hxx>
#include <IGESGeom_TransformationMatrix.hxx>
#include <IGESGraph_Color.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Message_ProgressIndicator.hxx>
#include <Message_ProgressScope.hxx>
#include <NCollection_DataMap.hxx>
#include <NCollection_Map.hxx>
#include <Poly_Triangulation.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_HArray2OfReal.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TDF_LabelMapHasher.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_ShapeMapHasher.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Iterator.hxx>
#include <TransferBRep.hxx>
#include <TransferBRep_ShapeMapper.hxx>
#include <Transfer_FinderProcess.hxx>
#include <Transfer_TransientProcess.hxx>
#include <UnitsMethods.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XSAlgo.hxx>
#include <XSAlgo_AlgoContainer.hxx>
#include <XSControl_TransferReader.hxx>
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

// The surface normal at each node of `face`'s triangulation, in the triangulation's frame (the face's location
// not applied), along the surface's own orientation (dU x dV), which is the side the triangles wind toward: the
// caller reverses both for a reversed face. Normals the triangulation carries are used as they are; otherwise the
// surface is evaluated at the node's UV. Where it has no normal there (a cone's apex, a sphere's pole, a
// degenerate patch) or the face has no UV nodes, the node gets the mean of the unit normals of its triangles.
std::vector<gp_Dir> node_normals(const TopoDS_Face& face, const Handle(Poly_Triangulation)& tri) {
  const Standard_Integer n = tri->NbNodes();
  std::vector<gp_Dir> out(n, gp::DZ());
  if (tri->HasNormals()) {
    for (Standard_Integer i = 1; i <= n; i++) out[i - 1] = tri->Normal(i);
    return out;
  }
  // Mean unit normal of the triangles around each node (the fallback).
  std::vector<gp_XYZ> mean(n, gp_XYZ(0, 0, 0));
  for (Standard_Integer k = 1; k <= tri->NbTriangles(); k++) {
    Standard_Integer a, b, c;
    tri->Triangle(k).Get(a, b, c);
    if (a < 1 || b < 1 || c < 1 || a > n || b > n || c > n) continue;
    gp_XYZ e = (tri->Node(b).XYZ() - tri->Node(a).XYZ()) ^ (tri->Node(c).XYZ() - tri->Node(a).XYZ());
    Standard_Real m = e.Modulus();
    if (!(m > Precision::Confusion() * Precision::Confusion())) continue;
    e /= m;
    mean[a - 1] += e;
    mean[b - 1] += e;
    mean[c - 1] += e;
  }
  // The surface in the triangulation's frame: the face without its own location (the TFace's surface location
  // stays, as for the triangulation).
  Handle(Geom_Surface) surf;
  if (tri->HasUVNodes()) surf = BRep_Tool::Surface(TopoDS::Face(face.Located(TopLoc_Location())));
  for (Standard_Integer i = 1; i <= n; i++) {
    gp_Dir d;
    if (!surf.IsNull() && GeomLib::NormEstim(surf, tri->UVNode(i), Precision::Confusion(), d) <= 1) {
      out[i - 1] = d;
    } else if (mean[i - 1].Modulus() > 1e-9) {
      out[i - 1] = gp_Dir(mean[i - 1]);
    }
  }
  return out;
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
      std::vector<float> nrm;
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
      bool reversed = face.Orientation() == TopAbs_REVERSED;
      std::vector<gp_Dir> normals = node_normals(face, tri);
      for (Standard_Integer i = 1; i <= tri->NbNodes(); i++) {
        gp_Pnt q = tri->Node(i).Transformed(t);
        p.pos.push_back((float)q.X());
        p.pos.push_back((float)q.Y());
        p.pos.push_back((float)q.Z());
        // The face's location is rigid (OCCT refuses scaled or mirrored ones), so a normal turns like a vector.
        gp_Dir n = normals[i - 1].Transformed(t);
        if (reversed) n.Reverse();
        p.nrm.push_back((float)n.X());
        p.nrm.push_back((float)n.Y());
        p.nrm.push_back((float)n.Z());
      }
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
      cb->primitive(cb->ctx, id, p.pos.data(), p.nrm.data(), p.pos.size() / 3, p.idx.data(), p.idx.size(),
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

// Closes an XCAF document however the function holding it ends.
struct Closer {
  Handle(XCAFApp_Application) app;
  Handle(TDocStd_Document) doc;
  ~Closer() {
    if (!doc.IsNull() && doc->IsOpened()) app->Close(doc);
  }
};

// OCCT's messages (transfer statistics) go to stdout by default: keep them out of the caller's output.
void quiet() {
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
}

// ---- IGES into the XCAF document ---------------------------------------------------------------------------------
//
// IGES states that a shape is placed several times with subfigures: a definition (308) holds geometry and/or
// instances (408) of other definitions; an instance places a definition (translation, scale, a 124 matrix). OCCT's
// transfer keeps that sharing: every instance of one definition is the same TShape under its own location. What
// IGESCAFControl_Reader::Transfer (7.6.3) then does with it loses part of it:
// - AddCompositeShape splits a definition holding both geometry and instances into a part and an unnamed
//   sub-assembly under a new compound, and builds both anew each time the definition is met from another root: that
//   geometry becomes one part per root placing it. Placed inside another definition, the new compound is left as an
//   extra free shape (drawn once more, unplaced) while the parent refers to the original compound, which XCAF then
//   makes an assembly of its raw sub-shapes (a plate becomes 6 parts named "FACE").
// - Names and colours are found by looking each entity's shape up in the document. Shape healing rebuilds each root
//   after its transfer, and XSAlgo_AlgoContainer::MergeTransferInfo leaves the binder of a nested 408 with the healed
//   shape without its location, so the lookup misses: instance names land on the part (the last instance's name
//   wins) and components keep XCAF's automatic names ("=>[0:1:1:2]").
// So IGES follows IGESCAFControl_Reader::Transfer's steps (units, TransferRoots, the colour and name pass over the
// entities) except two: the document is built from the root shapes with one label per TShape (IgesDoc::define), and
// the names, colours and blank status of subfigures and groups are read by walking each root entity alongside the
// shape it became (IgesDoc::walk). A file without subfigures (OCCT's IGES writer writes none: every occurrence is a
// copy) gets the same document as before: nothing in it is shared, so nothing is instanced.

bool iges_color(const Handle(IGESData_IGESEntity)& e, Quantity_Color& col) {
  if (e->DefColor() == IGESData_DefValue) {
    col = IGESCAFControl::DecodeColor(e->RankColor());
    return true;
  }
  if (e->DefColor() != IGESData_DefReference) return false;
  Handle(IGESGraph_Color) c = Handle(IGESGraph_Color)::DownCast(e->Color());
  if (c.IsNull()) return false;
  Standard_Real rgb[3];
  c->RGBIntensity(rgb[0], rgb[1], rgb[2]);
  for (Standard_Real& v : rgb) v = v < 0 ? 0 : (v > 100 ? 100 : v);
  col.SetValues(0.01 * rgb[0], 0.01 * rgb[1], 0.01 * rgb[2], Quantity_TOC_sRGB);
  return true;
}

std::string iges_name(const Handle(IGESData_IGESEntity)& e) {
  Handle(TCollection_HAsciiString) n;
  if (Handle(IGESBasic_SubfigureDef) d = Handle(IGESBasic_SubfigureDef)::DownCast(e)) n = d->Name();
  if ((n.IsNull() || n->IsEmpty()) && e->HasName()) n = e->NameValue();
  if (n.IsNull()) return std::string();
  TCollection_AsciiString s = n->String();
  s.LeftAdjust();
  s.RightAdjust();
  return std::string(s.ToCString());
}

// The entities a subfigure definition or group turned into the children of its compound, in order
// (IGESToBRep_CurveAndSurface::TransferGeometry skips items without a shape, and blanked ones when only visible
// entities are read); empty for other entities.
std::vector<Handle(IGESData_IGESEntity)> iges_items(const Handle(IGESData_IGESEntity)& e,
                                                    const Handle(Transfer_TransientProcess)& tp) {
  std::vector<Handle(IGESData_IGESEntity)> all;
  if (Handle(IGESBasic_SubfigureDef) d = Handle(IGESBasic_SubfigureDef)::DownCast(e)) {
    for (Standard_Integer i = 1; i <= d->NbEntities(); i++) all.push_back(d->AssociatedEntity(i));
  } else if (Handle(IGESBasic_Group) g = Handle(IGESBasic_Group)::DownCast(e)) {
    for (Standard_Integer i = 1; i <= g->NbEntities(); i++) all.push_back(g->Entity(i));
  }
  bool only_visible = Interface_Static::IVal("read.iges.onlyvisible") != 0;
  std::vector<Handle(IGESData_IGESEntity)> out;
  for (const Handle(IGESData_IGESEntity)& item : all) {
    if (item.IsNull() || (only_visible && item->BlankStatus() == 1)) continue;
    if (TransferBRep::ShapeResult(tp, item).IsNull()) continue;
    out.push_back(item);
  }
  return out;
}

std::vector<TopoDS_Shape> children(const TopoDS_Shape& s, bool cumulative) {
  std::vector<TopoDS_Shape> out;
  for (TopoDS_Iterator it(s, cumulative, cumulative); it.More(); it.Next()) out.push_back(it.Value());
  return out;
}

struct IgesDoc {
  // One definition: a compound placed by instances (or holding them), as a label of the document.
  struct Def {
    TDF_Label label;     // its part or assembly
    TopoDS_Shape shape;  // its shape in the document
    TDF_Label part;      // the part holding the compound's own geometry (null without any)
    bool lone = false;   // that geometry is one child of the compound, the part its shape (else their compound)
    std::vector<TDF_Label> components;  // per child of the compound: its component (null for geometry)
  };
  Handle(XCAFDoc_ShapeTool) st;
  Handle(XCAFDoc_ColorTool) ct;
  Handle(Transfer_TransientProcess) tp;
  NCollection_DataMap<TopoDS_Shape, bool, TopTools_ShapeMapHasher> composite_;
  NCollection_DataMap<TopoDS_Shape, size_t, TopTools_ShapeMapHasher> def_of;  // compound (unlocated) -> defs
  std::vector<Def> defs;
  std::vector<bool> walked;  // per definition: its entity's names and colours are set

  // A compound placed somewhere or holding one that is (IGESCAFControl_Reader's IsComposite): an instance of a
  // subfigure, a group with a transformation, or something holding them.
  bool composite(const TopoDS_Shape& s, int depth) {
    if (s.ShapeType() != TopAbs_COMPOUND) return false;
    if (!s.Location().IsIdentity()) return true;
    if (const bool* known = composite_.Seek(s)) return *known;
    if (depth > kMaxDepth) throw Failure{"the IGES subfigures nest deeper than 256 levels"};
    bool c = false;
    for (TopoDS_Iterator it(s, false, false); it.More() && !c; it.Next()) c = composite(it.Value(), depth + 1);
    composite_.Bind(s, c);
    return c;
  }

  static void forget_auto_name(const TDF_Label& l) { l.ForgetAttribute(TDataStd_Name::GetID()); }

  // The label for compound `s` (without location, placed somewhere), added once however often it is placed: a part
  // when it holds geometry only, else an assembly of its geometry children as one part (the child itself when there
  // is one) and its composite children as components.
  size_t define(const TopoDS_Shape& s, int depth) {
    if (const size_t* known = def_of.Seek(s)) return *known;
    if (depth > kMaxDepth) throw Failure{"the IGES subfigures nest deeper than 256 levels"};
    std::vector<TopoDS_Shape> kids = children(s, false);
    if (!composite(s, depth)) {
      // Geometry only (a subfigure of no instances, placed): one part.
      Def d;
      d.label = d.part = st->AddShape(s, Standard_False, Standard_False);
      d.shape = s;
      d.components.resize(kids.size());
      defs.push_back(d);
      def_of.Bind(s, defs.size() - 1);
      return defs.size() - 1;
    }
    std::vector<long> kid_def(kids.size(), -1);
    BRep_Builder b;
    TopoDS_Compound geometry, assembly;
    b.MakeCompound(geometry);
    b.MakeCompound(assembly);
    size_t n_geometry = 0, lone = 0;
    for (size_t i = 0; i < kids.size(); i++) {
      if (composite(kids[i], depth + 1)) {
        kid_def[i] = (long)define(kids[i].Located(TopLoc_Location()), depth + 1);
      } else {
        b.Add(geometry, kids[i]);
        n_geometry++;
        lone = i;
      }
    }
    Def d;
    if (n_geometry > 0) {
      // The part is placed where the lone child is (its shape without location), or is the compound of them all.
      TopoDS_Shape placed = n_geometry == 1 ? kids[lone] : TopoDS_Shape(geometry);
      d.part = st->AddShape(placed.Located(TopLoc_Location()), Standard_False, Standard_False);
      d.lone = n_geometry == 1;
      b.Add(assembly, placed);
    }
    for (size_t i = 0; i < kids.size(); i++) {
      if (kid_def[i] < 0) continue;
      TopoDS_Shape inst = defs[(size_t)kid_def[i]].shape.Located(kids[i].Location());
      inst.Orientation(kids[i].Orientation());
      b.Add(assembly, inst);
    }
    // Components come in the order of the compound's children (XCAFDoc_ShapeTool::addShape).
    d.label = st->AddShape(assembly, Standard_True, Standard_False);
    d.shape = assembly;
    TDF_LabelSequence comps;
    XCAFDoc_ShapeTool::GetComponents(d.label, comps, Standard_False);
    for (Standard_Integer i = 1; i <= comps.Length(); i++) forget_auto_name(comps.Value(i));
    Standard_Integer next = n_geometry > 0 ? 2 : 1;
    for (size_t i = 0; i < kids.size(); i++)
      d.components.push_back(kid_def[i] >= 0 && next <= comps.Length() ? comps.Value(next++) : TDF_Label());
    defs.push_back(d);
    def_of.Bind(s, defs.size() - 1);
    return defs.size() - 1;
  }

  // Adds one root shape; returns its label when it is composite (the placed definition), else a null label.
  TDF_Label add_root(const TopoDS_Shape& r) {
    if (!composite(r, 0)) {
      st->AddShape(r, Standard_False);
      return TDF_Label();
    }
    const Def& d = defs[define(r.Located(TopLoc_Location()), 0)];
    if (r.Location().IsIdentity()) return d.label;
    TopoDS_Shape placed = d.shape.Located(r.Location());
    placed.Orientation(r.Orientation());
    TDF_Label l = st->AddShape(placed, Standard_False, Standard_False);  // a reference to d.label
    if (l != d.label) forget_auto_name(l);
    return l;
  }

  void set_color(const TDF_Label& l, const Handle(IGESData_IGESEntity)& e) {
    Quantity_Color c;
    if (!l.IsNull() && iges_color(e, c)) ct->SetColor(l, c, XCAFDoc_ColorGen);
  }
  void set_name(const TDF_Label& l, const std::string& name) {
    if (!l.IsNull() && !name.empty()) TDataStd_Name::Set(l, TCollection_ExtendedString(name.c_str(), Standard_True));
  }

  // Entity `e` became shape `s` (as placed in its parent), placed by `occurrence` (a component or a root's
  // reference; null when the root is the definition itself). Sets the names, colours and blank status the subfigure
  // entities carry. Where the entities and shapes stop matching (shape healing dropped a child), it stops.
  void walk(const Handle(IGESData_IGESEntity)& e, const TopoDS_Shape& s, const TDF_Label& occurrence, int depth) {
    if (depth > kMaxDepth) throw Failure{"the IGES subfigures nest deeper than 256 levels"};
    const size_t* di = def_of.Seek(s.Located(TopLoc_Location()));
    if (!di) return;
    size_t index = *di;
    Handle(IGESData_IGESEntity) def_entity = e;
    if (Handle(IGESBasic_SingularSubfigure) inst = Handle(IGESBasic_SingularSubfigure)::DownCast(e)) {
      // The instance: its name, colour and blank status are the occurrence's.
      set_name(occurrence, iges_name(e));
      set_color(occurrence, e);
      if (!occurrence.IsNull() && e->BlankStatus() == 1) ct->SetVisibility(occurrence, Standard_False);
      def_entity = inst->Subfigure();
      if (def_entity.IsNull()) return;
    }
    if (!def_entity->IsKind(STANDARD_TYPE(IGESBasic_SubfigureDef)) &&
        !def_entity->IsKind(STANDARD_TYPE(IGESBasic_Group)))
      return;
    // The definition (once, however often it is placed): its name and colour, then what it holds.
    walked.resize(defs.size());
    if (walked[index]) return;
    walked[index] = true;
    const Def& d = defs[index];  // (walk adds no definitions: the reference stays valid)
    std::string name = iges_name(def_entity);
    set_name(d.label, name);
    set_color(d.label, def_entity);
    if (!d.lone) set_name(d.part, name);  // the definition's own geometry
    std::vector<Handle(IGESData_IGESEntity)> items = iges_items(def_entity, tp);
    std::vector<TopoDS_Shape> kids = children(s.Located(TopLoc_Location()), false);
    if (items.size() != kids.size() || kids.size() != d.components.size()) return;
    for (size_t i = 0; i < kids.size(); i++) {
      if (!d.components[i].IsNull()) {
        walk(items[i], kids[i], d.components[i], depth + 1);
      } else if (d.lone) {
        geometry(items[i], kids[i].Located(TopLoc_Location()), d.part, true, depth + 1);
      } else {
        geometry(items[i], kids[i], d.part, false, depth + 1);
      }
    }
  }

  // Geometry entity `e` became `s` in part `part` (in the part's coordinates): the whole part, or a piece of it.
  // Its name and colour go to the part, or (colour only) to the piece as a sub-shape, as IGESCAFControl_Reader does.
  void geometry(const Handle(IGESData_IGESEntity)& e, const TopoDS_Shape& s, const TDF_Label& part, bool whole,
                int depth) {
    if (part.IsNull() || depth > kMaxDepth) return;
    if (whole) {
      set_name(part, iges_name(e));
      set_color(part, e);
    } else {
      Quantity_Color c;
      if (iges_color(e, c)) {
        TDF_Label sub = st->AddSubShape(part, s);
        if (!sub.IsNull()) ct->SetColor(sub, c, XCAFDoc_ColorGen);
      }
    }
    if (!e->IsKind(STANDARD_TYPE(IGESBasic_Group))) return;
    std::vector<Handle(IGESData_IGESEntity)> items = iges_items(e, tp);
    std::vector<TopoDS_Shape> kids = children(s, true);
    if (items.size() != kids.size()) return;
    for (size_t i = 0; i < kids.size(); i++) geometry(items[i], kids[i], part, false, depth + 1);
  }
};

// IGESCAFControl_Reader::Transfer, with the document built by IgesDoc (see above).
bool iges_transfer(IGESCAFControl_Reader& reader, const Handle(TDocStd_Document)& doc,
                   const Message_ProgressRange& range) {
  Handle(IGESData_IGESModel) model = reader.IGESModel();
  if (model.IsNull()) return false;
  Standard_Real mm = 1.;
  if (!XCAFDoc_DocumentTool::GetLengthUnit(doc, mm, UnitsMethods_LengthUnit_Millimeter)) {
    XSAlgo::AlgoContainer()->PrepareForTransfer();
    mm = UnitsMethods::GetCasCadeLengthUnit();
    XCAFDoc_DocumentTool::SetLengthUnit(doc, mm, UnitsMethods_LengthUnit_Millimeter);
  }
  model->ChangeGlobalSection().SetCascadeUnit(mm);
  reader.TransferRoots(range);
  if (reader.NbShapes() <= 0) return false;

  IgesDoc d;
  d.st = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  d.ct = XCAFDoc_DocumentTool::ColorTool(doc->Main());
  const Handle(XSControl_TransferReader)& tr = reader.WS()->TransferReader();
  d.tp = tr->TransientProcess();
  // The roots' shapes, in TransferRoots's order, each with the entity it came from.
  NCollection_Map<TopoDS_Shape, TopTools_ShapeMapHasher> transferred;
  for (Standard_Integer i = 1; i <= reader.NbShapes(); i++) transferred.Add(reader.Shape(i));
  std::vector<std::pair<Handle(IGESData_IGESEntity), TopoDS_Shape>> roots;
  NCollection_Map<TopoDS_Shape, TopTools_ShapeMapHasher> added;
  for (Standard_Integer i = 1; i <= reader.NbRootsForTransfer(); i++) {
    Handle(IGESData_IGESEntity) e = Handle(IGESData_IGESEntity)::DownCast(reader.RootForTransfer(i));
    if (e.IsNull()) continue;
    TopoDS_Shape s = tr->ShapeResult(e);
    if (s.IsNull() || !transferred.Contains(s)) continue;
    roots.emplace_back(e, s);
    added.Add(s);
  }
  std::vector<TDF_Label> root_labels;
  for (auto& r : roots) root_labels.push_back(d.add_root(r.second));
  // Shapes TransferRoots kept that no root entity gives back (none expected): added as they are.
  for (Standard_Integer i = 1; i <= reader.NbShapes(); i++)
    if (!added.Contains(reader.Shape(i))) d.add_root(reader.Shape(i));

  // IGESCAFControl_Reader's pass over the entities (without layers), except subfigures: their shapes may not be the
  // document's (see above), and the walk below does them.
  for (Standard_Integer i = 1; i <= model->NbEntities(); i++) {
    Handle(IGESData_IGESEntity) e = model->Entity(i);
    if (e.IsNull() || e->IsKind(STANDARD_TYPE(IGESBasic_SubfigureDef)) ||
        e->IsKind(STANDARD_TYPE(IGESBasic_SingularSubfigure)))
      continue;
    Handle(Transfer_Binder) binder = d.tp->Find(e);
    if (binder.IsNull()) continue;
    TopoDS_Shape s = TransferBRep::ShapeResult(binder);
    if (s.IsNull()) continue;
    Quantity_Color col;
    bool has_color = iges_color(e, col);
    if (has_color) d.ct->AddColor(col);
    TDF_Label l;
    if (d.st->SearchUsingMap(s, l, Standard_False, has_color)) {
      if (has_color) d.ct->SetColor(l, col, XCAFDoc_ColorGen);
      d.set_name(l, iges_name(e));
    } else if (has_color) {
      for (TopoDS_Iterator it(s); it.More(); it.Next())
        if (d.st->SearchUsingMap(it.Value(), l, Standard_False, Standard_True))
          d.ct->SetColor(l, col, XCAFDoc_ColorGen);
    }
  }
  for (size_t i = 0; i < roots.size(); i++) {
    if (root_labels[i].IsNull()) continue;
    const IgesDoc::Def& def = d.defs[*d.def_of.Seek(roots[i].second.Located(TopLoc_Location()))];
    d.walk(roots[i].first, roots[i].second, root_labels[i] == def.label ? TDF_Label() : root_labels[i], 0);
  }
  d.ct->ReverseChainsOfTreeNodes();
  d.st->UpdateAssemblies();
  return true;
}

int read_impl(const char* path, int32_t format, const hr_tessellation* tess, const hr_callbacks* cb,
              hr_units* units) {
  quiet();
  Handle(Progress) progress = new Progress(cb);
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  Closer closer{app, doc};
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
    if (!iges_transfer(reader, doc, progress->Start())) {
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

// IGES with subfigures, for tests (OCCT's IGES writer writes none: every occurrence of a part is a copy). Every part
// is a subfigure definition (308) of its geometry and every assembly a 308 of instances (408) of its components, with
// names (406 form 15 on instances, the 308's own name), colours (an occurrence's on its 408, a part's on its 308, a
// face's on its face entity) and hidden occurrences (blank status). A part placed once, where its assembly is, with
// no name, colour or visibility of its own on the occurrence nor a colour of its own, is written inline in the
// assembly's 308: geometry beside instances, as CAD systems also write it.
struct SubfigureWriter {
  IGESControl_Writer w{"MM", 0};
  Handle(XCAFDoc_ShapeTool) st;
  Handle(XCAFDoc_ColorTool) ct;
  Handle(Transfer_FinderProcess) fp = new Transfer_FinderProcess;
  BRepToIGES_BREntity brep;
  NCollection_DataMap<TDF_Label, Handle(IGESBasic_SubfigureDef), TDF_LabelMapHasher> defs;
  NCollection_DataMap<TDF_Label, int, TDF_LabelMapHasher> uses;  // components referring to a label

  SubfigureWriter(const Handle(XCAFDoc_ShapeTool)& st_, const Handle(XCAFDoc_ColorTool)& ct_) : st(st_), ct(ct_) {
    brep.SetModel(w.Model());
    brep.SetTransferProcess(fp);
    TDF_LabelSequence all;
    st->GetShapes(all);
    for (Standard_Integer i = 1; i <= all.Length(); i++) {
      TDF_LabelSequence comps;
      XCAFDoc_ShapeTool::GetComponents(all.Value(i), comps, Standard_False);
      for (Standard_Integer k = 1; k <= comps.Length(); k++) {
        TDF_Label ref;
        if (!XCAFDoc_ShapeTool::GetReferredShape(comps.Value(k), ref)) continue;
        if (int* n = uses.ChangeSeek(ref)) (*n)++;
        else uses.Bind(ref, 1);
      }
    }
  }

  void name(const Handle(IGESData_IGESEntity)& e, const std::string& n) {
    if (n.empty()) return;
    Handle(IGESBasic_Name) p = new IGESBasic_Name;
    p->Init(1, new TCollection_HAsciiString(n.c_str()));
    e->AddProperty(p);
    w.AddEntity(p);
  }

  void color(const Handle(IGESData_IGESEntity)& e, const TDF_Label& l) {
    Quantity_Color c;
    if (!ct->GetColor(l, XCAFDoc_ColorSurf, c) && !ct->GetColor(l, XCAFDoc_ColorGen, c)) return;
    if (Standard_Integer rank = IGESCAFControl::EncodeColor(c)) {
      e->InitColor(Handle(IGESData_ColorEntity)(), rank);
      return;
    }
    Standard_Real r, g, b;
    c.Values(r, g, b, Quantity_TOC_sRGB);
    Handle(IGESGraph_Color) ce = new IGESGraph_Color;
    ce->Init(100 * r, 100 * g, 100 * b, new TCollection_HAsciiString());
    w.AddEntity(ce);
    e->InitColor(ce);
  }

  // The geometry of part `l`, its faces' colours on their face entities.
  Handle(IGESData_IGESEntity) geometry(const TDF_Label& l) {
    Handle(IGESData_IGESEntity) e = brep.TransferShape(XCAFDoc_ShapeTool::GetShape(l));
    if (e.IsNull()) throw Failure{"OpenCASCADE could not write a part as IGES"};
    TDF_LabelSequence subs;
    XCAFDoc_ShapeTool::GetSubShapes(l, subs);
    for (Standard_Integer i = 1; i <= subs.Length(); i++) {
      for (TopExp_Explorer f(XCAFDoc_ShapeTool::GetShape(subs.Value(i)), TopAbs_FACE); f.More(); f.Next()) {
        Handle(IGESData_IGESEntity) fe;
        if (fp->FindTypedTransient(TransferBRep::ShapeMapper(fp, f.Current()), STANDARD_TYPE(IGESData_IGESEntity), fe))
          color(fe, subs.Value(i));
      }
    }
    return e;
  }

  // A component's name, without XCAF's automatic one ("=>[0:1:1:2]", the label it refers to).
  static std::string occurrence_name(const TDF_Label& c) {
    std::string n = label_name(c);
    return n.rfind("=>[", 0) == 0 ? std::string() : n;
  }

  static bool is_identity(const gp_Trsf& t) {
    for (int r = 1; r <= 3; r++)
      for (int c = 1; c <= 4; c++)
        if (t.Value(r, c) != (r == c ? 1.0 : 0.0)) return false;
    return true;
  }

  // The 308 of label `l` (a part or an assembly), `level` deep in the assembly.
  Handle(IGESBasic_SubfigureDef) definition(const TDF_Label& l, int level) {
    if (const Handle(IGESBasic_SubfigureDef)* known = defs.Seek(l)) return *known;
    if (level > kMaxDepth) throw Failure{"the assembly is deeper than 256 levels"};
    std::vector<Handle(IGESData_IGESEntity)> items;
    Standard_Integer depth = 0;  // the 308's nesting of subfigures (0: no instances inside)
    if (XCAFDoc_ShapeTool::IsAssembly(l)) {
      TDF_LabelSequence comps;
      XCAFDoc_ShapeTool::GetComponents(l, comps, Standard_False);
      for (Standard_Integer i = 1; i <= comps.Length(); i++) {
        TDF_Label c = comps.Value(i), ref;
        if (!XCAFDoc_ShapeTool::GetReferredShape(c, ref)) continue;
        std::array<float, 4> unused;
        bool inline_ = !XCAFDoc_ShapeTool::IsAssembly(ref) && uses.Find(ref) == 1 &&
                       is_identity(XCAFDoc_ShapeTool::GetLocation(c).Transformation()) && occurrence_name(c).empty() &&
                       !label_color(ct, c, unused) && ct->IsVisible(c) && !label_color(ct, ref, unused);
        if (inline_) {
          Handle(IGESData_IGESEntity) g = geometry(ref);
          name(g, label_name(ref));
          items.push_back(g);
        } else {
          Handle(IGESBasic_SingularSubfigure) inst = instance(c, ref, level);
          depth = std::max(depth, inst->Subfigure()->Depth() + 1);
          items.push_back(inst);
        }
      }
    } else {
      items.push_back(geometry(l));
    }
    if (items.empty()) throw Failure{"an empty assembly"};
    Handle(IGESData_HArray1OfIGESEntity) array = new IGESData_HArray1OfIGESEntity(1, (Standard_Integer)items.size());
    for (size_t i = 0; i < items.size(); i++) array->SetValue((Standard_Integer)i + 1, items[i]);
    Handle(IGESBasic_SubfigureDef) d = new IGESBasic_SubfigureDef;
    d->Init(depth, new TCollection_HAsciiString(label_name(l).c_str()), array);
    color(d, l);
    defs.Bind(l, d);
    return d;
  }

  // The 408 placing `ref` as component `c`: a translation, or a 124 matrix when it also turns.
  Handle(IGESBasic_SingularSubfigure) instance(const TDF_Label& c, const TDF_Label& ref, int level) {
    gp_Trsf t = XCAFDoc_ShapeTool::GetLocation(c).Transformation();
    Handle(IGESBasic_SingularSubfigure) inst = new IGESBasic_SingularSubfigure;
    bool turns = t.Form() != gp_Identity && t.Form() != gp_Translation;
    inst->Init(definition(ref, level + 1), turns ? gp_XYZ() : t.TranslationPart(), Standard_False, 1.0);
    if (turns) {
      Handle(TColStd_HArray2OfReal) m = new TColStd_HArray2OfReal(1, 3, 1, 4);
      for (int r = 1; r <= 3; r++)
        for (int k = 1; k <= 4; k++) m->SetValue(r, k, t.Value(r, k));
      Handle(IGESGeom_TransformationMatrix) tm = new IGESGeom_TransformationMatrix;
      tm->Init(m);
      w.AddEntity(tm);
      inst->InitTransf(tm);
    }
    name(inst, occurrence_name(c));
    color(inst, c);
    if (!ct->IsVisible(c))
      inst->InitStatus(1, inst->SubordinateStatus(), inst->UseFlag(), inst->HierarchyStatus());
    return inst;
  }

  // Free assemblies and coloured free parts as instances of their 308, other free parts as their geometry.
  bool write(const char* path) {
    TDF_LabelSequence roots;
    st->GetFreeShapes(roots);
    for (Standard_Integer i = 1; i <= roots.Length(); i++) {
      TDF_Label l = roots.Value(i);
      std::array<float, 4> unused;
      Handle(IGESData_IGESEntity) e;
      if (XCAFDoc_ShapeTool::IsAssembly(l) || label_color(ct, l, unused)) {
        Handle(IGESBasic_SingularSubfigure) inst = new IGESBasic_SingularSubfigure;
        inst->Init(definition(l, 0), gp_XYZ(), Standard_False, 1.0);
        e = inst;
      } else {
        e = geometry(l);
      }
      name(e, label_name(l));
      w.AddEntity(e);
    }
    return w.Write(path);
  }
};

int write_impl(const char* path, int32_t format, int32_t kind, int32_t count) {
  quiet();
  // Without p-curves a box takes about a third of the entities.
  Interface_Static::SetIVal("write.surfacecurve.mode", kind == 3 ? 0 : 1);
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  Closer closer{app, doc};
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
  } else if (kind == 1 || kind == 4) {
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
    if (kind == 4) {
      TDF_Label pair = st->NewShape();
      TDataStd_Name::Set(pair, "two_patterns");
      TDataStd_Name::Set(st->AddComponent(pair, asm_, at(0, 0, 0)), "left");
      TDataStd_Name::Set(st->AddComponent(pair, asm_, at(200, 0, 0)), "right");
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
  } else if (kind == 5) {
    // One cylinder (radius 10, height 20, axis z) placed as is and turned upside down 50 mm along x.
    TDF_Label asm_ = st->NewShape();
    TDataStd_Name::Set(asm_, "cylinders");
    TDF_Label cyl = st->AddShape(BRepPrimAPI_MakeCylinder(10.0, 20.0).Shape(), false);
    TDataStd_Name::Set(cyl, "cylinder");
    TDataStd_Name::Set(st->AddComponent(asm_, cyl, TopLoc_Location()), "upright");
    gp_Trsf flip;
    flip.SetRotation(gp::OX(), M_PI);
    flip.SetTranslationPart(gp_Vec(50, 0, 20));
    TDataStd_Name::Set(st->AddComponent(asm_, cyl, TopLoc_Location(flip)), "upside_down");
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
  } else if (format == 1) {
    IGESControl_Controller::Init();
    IGESCAFControl_Writer w;
    ok = w.Transfer(doc) && w.Write(path);
  } else if (format == 2) {
    IGESControl_Controller::Init();
    ok = SubfigureWriter(st, ct).write(path);
  } else {
    throw Failure{"unknown test file format"};
  }
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
