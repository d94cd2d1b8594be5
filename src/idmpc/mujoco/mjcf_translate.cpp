#include "idmpc/mujoco/mjcf_translate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include <tinyxml2.h>

#include "idmpc/mujoco/gravcomp.hpp"

namespace idmpc::mj {
namespace {

namespace fs = std::filesystem;
using tinyxml2::XMLElement;

constexpr int kMaxIncludeDepth = 16;

// actuator elements; in MuJoCo's default classes they all set the one actuator default
const std::set<std::string> kActuatorTags = {"general",  "motor",    "position", "velocity", "intvelocity",
                                             "damper",   "cylinder", "muscle",   "adhesion", "plugin"};
const std::set<std::string> kServoShortcuts = {"position", "intvelocity"};

// elements of MuJoCo >= 2.3 with nothing like them in MuJoCo 2.2
const std::map<std::string, std::string> kNewerElements = {
    {"replicate", "repeated subtrees are expanded by MuJoCo >= 3.0 only"},
    {"frame", "frames are a MuJoCo >= 3.0 element"},
    {"flex", "deformable flex objects do not exist in MuJoCo 2.2"},
    {"flexcomp", "deformable flex objects do not exist in MuJoCo 2.2"},
    {"plugin", "engine plugins do not exist in MuJoCo 2.2"},
    {"extension", "engine plugins do not exist in MuJoCo 2.2"},
    {"instance", "engine plugins do not exist in MuJoCo 2.2"},
    {"attach", "model attachment is a MuJoCo >= 3.2 element"},
    {"layer", "layered textures are a MuJoCo >= 3.2 element"}};

// attributes of MuJoCo >= 2.3 without a MuJoCo 2.2 equivalent (at least at the value given)
const std::map<std::string, std::string> kNewerAttributes = {
    {"gravcomp", "gravity compensation forces do not exist in MuJoCo 2.2"},
    {"actuatorgravcomp", "gravity compensation through the actuators does not exist in MuJoCo 2.2"},
    {"actearly", "MuJoCo 2.2 always applies the actuator force of the previous activation"},
    {"actdim", "MuJoCo 2.2 actuators have one activation at most"},
    {"maxhullvert", "MuJoCo 2.2 always uses the full convex hull of a mesh for collisions"},
    {"eulerdamp", "MuJoCo 2.2's Euler integrator always treats damping implicitly"},
    {"nsample", "actuator history (delays) does not exist in MuJoCo 2.2"},
    {"interp", "actuator history (delays) does not exist in MuJoCo 2.2"},
    {"delay", "actuator history (delays) does not exist in MuJoCo 2.2"}};

// attributes of cameras and lights that MuJoCo 2.2 does not have: they change what a camera
// renders or how a light shines, never the dynamics, and are dropped (said in one notice)
const std::map<std::string, std::set<std::string>> kRenderOnlyAttributes = {
    {"camera", {"resolution", "focal", "focalpixel", "principal", "principalpixel", "sensorsize", "orthographic"}},
    {"light", {"type", "texture", "intensity", "range", "bulbradius"}}};

std::string number(double x) {
  std::ostringstream o;
  o.precision(10);
  o << x;
  return o.str();
}

std::string trimmed(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
}

std::vector<double> numbers(const std::string& text) {
  std::vector<double> out;
  std::istringstream in(text);
  double x;
  while (in >> x) out.push_back(x);
  return out;
}

// one file of the model
struct Source {
  std::string path;
  std::unique_ptr<tinyxml2::XMLDocument> doc;
  bool changed = false;
};

// an element of the model with includes expanded: its logical parent is the element holding
// the <include>
struct Node {
  XMLElement* e = nullptr;
  Source* src = nullptr;
  Node* parent = nullptr;
  std::vector<Node*> children;
  std::string tag() const { return e->Name(); }
  std::string get(const char* name, const std::string& fallback = "") const {
    const char* v = e->Attribute(name);
    return v ? v : fallback;
  }
  bool has(const char* name) const { return e->Attribute(name) != nullptr; }
};

class MjcfTree {
 public:
  explicit MjcfTree(const std::string& path) : main_dir_(fs::path(path).parent_path()) {
    Source* main = load(path);
    if (!main) return;
    XMLElement* root = main->doc->RootElement();
    if (!root || std::string(root->Name()) != "mujoco") return;
    root_ = make(root, main, nullptr);
    expand(root_, root, main, 0);
    ok_ = true;
  }
  bool ok() const { return ok_; }
  Node* root() const { return root_; }
  std::vector<std::unique_ptr<Source>>& sources() { return sources_; }

  // "<joint> 'j1', line 12" (or "…, arm.xml line 12" in an included file)
  std::string where(const Node* n) const {
    std::string out = "<" + n->tag() + ">";
    if (n->has("name")) out += " '" + n->get("name") + "'";
    if (n->has("class") && n->tag() == "default") out += " '" + n->get("class") + "'";
    out += ", ";
    if (n->src != sources_.front().get()) out += n->src->path + " ";
    return out + "line " + std::to_string(n->e->GetLineNum());
  }

 private:
  Source* load(const std::string& path) {
    auto src = std::make_unique<Source>();
    src->path = path;
    src->doc = std::make_unique<tinyxml2::XMLDocument>(true, tinyxml2::PRESERVE_WHITESPACE);
    if (src->doc->LoadFile(path.c_str()) != tinyxml2::XML_SUCCESS) return nullptr;
    sources_.push_back(std::move(src));
    return sources_.back().get();
  }
  Node* make(XMLElement* e, Source* src, Node* parent) {
    nodes_.push_back(std::make_unique<Node>());
    Node* n = nodes_.back().get();
    n->e = e;
    n->src = src;
    n->parent = parent;
    if (parent) parent->children.push_back(n);
    return n;
  }
  // children of `xml` (in `src`) become children of `node`; an <include> is replaced by the
  // children of the included file's root, as MuJoCo does
  void expand(Node* node, XMLElement* xml, Source* src, int depth) {
    for (XMLElement* c = xml->FirstChildElement(); c; c = c->NextSiblingElement()) {
      if (std::string(c->Name()) == "include" && c->Attribute("file")) {
        const fs::path file(c->Attribute("file"));
        const std::string path = (file.is_absolute() ? file : main_dir_ / file).string();
        Source* inc = depth < kMaxIncludeDepth ? load(path) : nullptr;
        // an unreadable include is MuJoCo's to report
        if (inc && inc->doc->RootElement()) expand(node, inc->doc->RootElement(), inc, depth + 1);
        continue;
      }
      expand(make(c, src, node), c, src, depth);
    }
  }

  fs::path main_dir_;
  std::vector<std::unique_ptr<Source>> sources_;
  std::vector<std::unique_ptr<Node>> nodes_;
  Node* root_ = nullptr;
  bool ok_ = false;
};

// --------------------------------------------------------------------------------------------
// default classes

class Defaults {
 public:
  explicit Defaults(Node* root) {
    for (Node* c : root->children) {
      if (c->tag() == "default") add(c, "");
    }
  }
  // the class an element uses: its own, else (in the body tree) the nearest childclass
  static std::string class_of(const Node* n) {
    if (n->has("class")) return n->get("class");
    for (const Node* p = n->parent; p; p = p->parent) {
      if (p->has("childclass")) return p->get("childclass");
    }
    return "main";
  }
  // the value of `name` for element `n` (of one of `tags` in defaults), with the node that gives
  // it: the element itself, else the nearest class defining it (within a class, the last)
  std::optional<std::pair<std::string, const Node*>> resolve(const Node* n, const std::set<std::string>& tags,
                                                              const char* name) const {
    if (n->has(name)) return std::make_pair(n->get(name), n);
    for (std::string cls = class_of(n); !cls.empty();) {
      const auto it = classes_.find(cls);
      if (it == classes_.end()) break;
      const Node* d = it->second.node;
      for (auto c = d->children.rbegin(); c != d->children.rend(); ++c) {
        if (tags.count((*c)->tag()) && (*c)->has(name)) return std::make_pair((*c)->get(name), *c);
      }
      cls = it->second.parent;
    }
    return std::nullopt;
  }
  // class chain of `n`, nearest first
  std::vector<const Node*> chain(const Node* n) const {
    std::vector<const Node*> out;
    for (std::string cls = class_of(n); !cls.empty();) {
      const auto it = classes_.find(cls);
      if (it == classes_.end()) break;
      out.push_back(it->second.node);
      cls = it->second.parent;
    }
    return out;
  }

 private:
  struct Class {
    const Node* node;
    std::string parent;
  };
  void add(const Node* d, const std::string& parent) {
    const std::string name = d->get("class", parent.empty() ? "main" : "");
    classes_[name] = Class{d, parent};
    for (const Node* c : d->children) {
      if (c->tag() == "default") add(c, name);
    }
  }
  std::map<std::string, Class> classes_;
};

// --------------------------------------------------------------------------------------------
// the text MuJoCo parses: every element on the line it had, so that MuJoCo's messages name the
// user's lines

class LinePrinter {
 public:
  std::string print(const tinyxml2::XMLDocument& doc) {
    for (const tinyxml2::XMLNode* n = doc.FirstChild(); n; n = n->NextSibling()) node(n);
    out_ += '\n';
    return out_;
  }

 private:
  void pad(int line) {
    for (; line_ < line; ++line_) out_ += '\n';
  }
  void emit(const std::string& s) {
    out_ += s;
    line_ += static_cast<int>(std::count(s.begin(), s.end(), '\n'));
  }
  static std::string escape(const char* s, bool attribute) {
    std::string out;
    for (; *s; ++s) {
      switch (*s) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += attribute ? ">" : "&gt;"; break;
        case '"': out += attribute ? "&quot;" : "\""; break;
        default: out += *s;
      }
    }
    return out;
  }
  void node(const tinyxml2::XMLNode* n) {
    if (const XMLElement* e = n->ToElement()) {
      if (e->GetLineNum() > 0) pad(e->GetLineNum());
      emit(std::string("<") + e->Name());
      for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
        emit(std::string(" ") + a->Name() + "=\"" + escape(a->Value(), true) + "\"");
      }
      if (!e->FirstChild()) {
        emit("/>");
        return;
      }
      emit(">");
      for (const tinyxml2::XMLNode* c = e->FirstChild(); c; c = c->NextSibling()) node(c);
      emit(std::string("</") + e->Name() + ">");
    } else if (const tinyxml2::XMLText* t = n->ToText()) {
      emit(t->CData() ? std::string("<![CDATA[") + t->Value() + "]]>" : escape(t->Value(), false));
    } else if (n->ToComment()) {
      pad(n->GetLineNum());
      emit(std::string("<!--") + n->Value() + "-->");
    } else if (n->ToDeclaration()) {
      pad(n->GetLineNum());
      emit(std::string("<?") + n->Value() + "?>");
    } else if (n->ToUnknown()) {
      pad(n->GetLineNum());
      emit(std::string("<!") + n->Value() + ">");
    }
  }
  std::string out_;
  int line_ = 1;
};

// --------------------------------------------------------------------------------------------
// the translation

class Translator {
 public:
  Translator(MjcfTree& model, MjcfTranslation& out, const Weld* weld)
      : model_(model), defaults_(model.root()), out_(out), weld_(weld) {}

  void run() {
    collect(model_.root());
    // everything is resolved on the file as written, before any edit
    plan_autolimits();
    plan_actuators();
    plan_joints();
    scan_newer_names();
    if (weld_) plan_weld(*weld_);
    edit_text();
  }

 private:
  void collect(Node* n) {
    for (Node* c : n->children) {
      const std::string tag = c->tag();
      if (tag == "compiler") compilers_.push_back(c);
      if (tag == "actuator" && n == model_.root()) {
        for (Node* a : c->children) actuators_.push_back(a);
      }
      if (tag == "tendon" && n == model_.root()) {
        for (Node* t : c->children) tendons_.push_back(t);
      }
      if (tag == "worldbody" && n == model_.root()) bodies(c);
      all_.push_back(c);
      collect(c);
    }
  }
  // joints in MuJoCo's order: bodies depth first in document order, each body's joints in order
  void bodies(Node* body) {
    for (Node* c : body->children) {
      if (c->tag() == "joint" || c->tag() == "freejoint") joints_.push_back(c);
    }
    for (Node* c : body->children) {
      if (c->tag() != "body") continue;
      body_node_[next_body_] = c;
      body_id_[c] = next_body_++;  // MuJoCo numbers bodies in this depth-first order
      bodies(c);
    }
  }

  // the welded joints leave the text, their bodies placed where the joints held them; what
  // names them goes too, and the keyframes and sensors, whose sizes change; the patches of the
  // compiled model follow the new actuator and joint numbers
  void plan_weld(const Weld& w) {
    std::set<int> joints;
    std::set<std::string> names;
    for (const int j : w.joints) {
      if (j < 0 || j >= static_cast<int>(joints_.size())) {
        throw std::invalid_argument("cannot weld joint #" + std::to_string(j) + ": the file has " +
                                    std::to_string(joints_.size()) + " joints");
      }
      joints.insert(j);
      if (joints_[j]->has("name")) names.insert(joints_[j]->get("name"));
      remove_element_.push_back(joints_[j]);
    }
    for (const Weld::Body& b : w.bodies) {
      const auto it = body_node_.find(b.body);
      if (it == body_node_.end()) throw std::invalid_argument("cannot place body #" + std::to_string(b.body));
      std::ostringstream pos, quat;
      pos.precision(17);
      quat.precision(17);
      pos << b.pos[0] << ' ' << b.pos[1] << ' ' << b.pos[2];
      quat << b.quat[0] << ' ' << b.quat[1] << ' ' << b.quat[2] << ' ' << b.quat[3];
      set_attr_.push_back({it->second, "pos", pos.str()});
      set_attr_.push_back({it->second, "quat", quat.str()});
      for (const char* other : {"euler", "axisangle", "xyaxes", "zaxis"}) {
        if (it->second->has(other)) remove_attr_.emplace_back(it->second, other);
      }
    }
    std::set<std::string> tendons;
    for (Node* t : tendons_) {
      if (t->tag() != "fixed") continue;
      int welded = 0, total = 0;
      for (const Node* c : t->children) {
        if (c->tag() != "joint") continue;
        ++total;
        welded += names.count(c->get("joint")) > 0;
      }
      if (welded == 0) continue;
      if (welded < total) {
        throw std::invalid_argument("fixed tendon " + model_.where(t) +
                                    " couples held joints with joints the controller drives, which idmpc does "
                                    "not model");
      }
      tendons.insert(t->get("name"));
      remove_element_.push_back(t);
    }
    std::vector<int> actuators;
    for (std::size_t u = 0; u < actuators_.size(); ++u) {
      Node* a = actuators_[u];
      if (names.count(a->get("joint")) || names.count(a->get("jointinparent")) ||
          (a->has("tendon") && tendons.count(a->get("tendon")))) {
        actuators.push_back(static_cast<int>(u));
        remove_element_.push_back(a);
      }
    }
    for (Node* section : model_.root()->children) {
      if (section->tag() == "keyframe" || section->tag() == "sensor") remove_element_.push_back(section);
      if (section->tag() != "equality") continue;
      for (Node* c : section->children) {
        if ((c->tag() == "joint" && (names.count(c->get("joint1")) || names.count(c->get("joint2")))) ||
            (c->tag() == "tendon" && (tendons.count(c->get("tendon1")) || tendons.count(c->get("tendon2"))))) {
          remove_element_.push_back(c);
        }
      }
    }
    // the patches by the numbers of the welded text
    auto renumber = [](int& index, const std::vector<int>& removed) {
      const auto below = std::lower_bound(removed.begin(), removed.end(), index);
      if (below != removed.end() && *below == index) return false;
      index -= static_cast<int>(below - removed.begin());
      return true;
    };
    const std::vector<int> removed_joints(joints.begin(), joints.end());
    std::vector<ActuatorPatch> kept_actuators;
    for (ActuatorPatch p : out_.actuators) {
      if (renumber(p.actuator, actuators)) kept_actuators.push_back(p);
    }
    out_.actuators = std::move(kept_actuators);
    std::vector<JointForcePatch> kept_joints;
    for (JointForcePatch p : out_.joints) {
      if (renumber(p.joint, removed_joints)) kept_joints.push_back(p);
    }
    out_.joints = std::move(kept_joints);
    welded_ = true;
  }

  std::optional<std::pair<std::string, const Node*>> resolve(const Node* n, const std::set<std::string>& tags,
                                                              const char* name) const {
    return defaults_.resolve(n, tags, name);
  }
  bool autolimits_given() const {
    return std::any_of(compilers_.begin(), compilers_.end(), [](const Node* c) { return c->has("autolimits"); });
  }
  // MuJoCo >= 3.0.0 limits a range given without its flag unless the file says autolimits="false"
  bool autolimits_on() const {
    bool on = true;
    for (const Node* c : compilers_) {
      if (c->has("autolimits")) on = c->get("autolimits") == "true";
    }
    return on;
  }

  void plan_autolimits() {
    if (autolimits_given()) return;
    std::vector<std::string> ranged;
    auto check = [&](const Node* n, const std::set<std::string>& tags, const char* range, const char* flag) {
      if (resolve(n, tags, range) && !resolve(n, tags, flag)) {
        ranged.push_back(n->tag() + (n->has("name") ? " '" + n->get("name") + "'" : "") + " " + range);
      }
    };
    for (const Node* j : joints_) check(j, {"joint"}, "range", "limited");
    for (const Node* t : tendons_) check(t, {"tendon"}, "range", "limited");
    for (const Node* a : actuators_) {
      check(a, kActuatorTags, "ctrlrange", "ctrllimited");
      check(a, kActuatorTags, "forcerange", "forcelimited");
      check(a, kActuatorTags, "actrange", "actlimited");
    }
    if (ranged.empty()) return;
    set_autolimits_ = true;
    std::string list;
    for (std::size_t k = 0; k < ranged.size() && k < 3; ++k) list += (k ? ", " : "") + ranged[k];
    if (ranged.size() > 3) list += " and " + std::to_string(ranged.size() - 3) + " more";
    out_.notices.push_back({"autolimits", "<compiler autolimits> set to true, MuJoCo >= 3.0.0's default (earlier versions' is false): " +
                           std::to_string(ranged.size()) + " range(s) without their limited flag limit (" +
                           list + ")"});
  }

  // biasprm[2] of a position/intvelocity shortcut as MuJoCo >= 2.3 resolves it: the element's
  // kv or dampratio, else the nearest class's (a shortcut's kv/dampratio, a general's biasprm,
  // a velocity's kv); MuJoCo 2.2's shortcut clears it
  std::optional<std::pair<double, std::string>> servo_bias(const Node* a) const {
    auto from = [&](const Node* n) -> std::optional<std::pair<double, std::string>> {
      const std::string where = n == a ? "" : " (class '" + Defaults::class_of(a) + "', " + model_.where(n) + ")";
      const std::string tag = n->tag();
      if (kServoShortcuts.count(tag) && n->has("kv")) {
        return std::make_pair(-std::atof(n->get("kv").c_str()), "kv " + n->get("kv") + where);
      }
      if (kServoShortcuts.count(tag) && n->has("dampratio")) {
        return std::make_pair(std::atof(n->get("dampratio").c_str()), "dampratio " + n->get("dampratio") + where);
      }
      if (n == a) return std::nullopt;
      if (tag == "general" && n->has("biasprm")) {
        const std::vector<double> b = numbers(n->get("biasprm"));
        if (b.size() >= 3) return std::make_pair(b[2], "biasprm[2] " + number(b[2]) + where);
      }
      if (tag == "velocity" && n->has("kv")) {
        return std::make_pair(-std::atof(n->get("kv").c_str()), "kv " + n->get("kv") + " of a <velocity>" + where);
      }
      return std::nullopt;
    };
    if (auto own = from(a)) return own;
    for (const Node* d : defaults_.chain(a)) {
      for (auto c = d->children.rbegin(); c != d->children.rend(); ++c) {
        if (!kActuatorTags.count((*c)->tag())) continue;
        if (auto v = from(*c)) return v;
      }
    }
    return std::nullopt;
  }

  void plan_actuators() {
    for (std::size_t u = 0; u < actuators_.size(); ++u) {
      const Node* a = actuators_[u];
      if (!kServoShortcuts.count(a->tag())) continue;
      ActuatorPatch p;
      p.actuator = static_cast<int>(u);
      p.where = model_.where(a);
      p.activation = a->tag() == "intvelocity";
      if (a->has("kv") && a->has("dampratio")) {
        untranslatable(a, "kv", "kv and dampratio cannot both be given (MuJoCo >= 2.3 refuses it too)");
      }
      if (const auto bias = servo_bias(a); bias && bias->first != 0) {
        p.set_bias = true;
        p.bias = bias->first;
        p.bias_source = bias->second;
      }
      if (const auto r = resolve(a, kServoShortcuts, "inheritrange")) {
        p.inheritrange = std::atof(r->first.c_str());
        const char* range = p.activation ? "actrange" : "ctrlrange";
        const auto given = resolve(a, kActuatorTags, range);
        if (p.inheritrange > 0 && given) {
          const std::vector<double> v = numbers(given->first);
          if (std::any_of(v.begin(), v.end(), [](double x) { return x != 0; })) {
            untranslatable(a, "inheritrange", std::string(range) + " and inheritrange cannot both be given " +
                                                  "(MuJoCo >= 2.3 refuses it too)");
            p.inheritrange = 0;
          }
        }
      }
      if (p.set_bias || p.inheritrange > 0) out_.actuators.push_back(p);
    }
  }

  void plan_joints() {
    for (std::size_t j = 0; j < joints_.size(); ++j) {
      const Node* n = joints_[j];
      bool force_range = false;
      if (const auto range = resolve(n, {"joint"}, "actuatorfrcrange")) {
        const auto flag = resolve(n, {"joint"}, "actuatorfrclimited");
        const bool limited = flag ? flag->first == "true" : autolimits_on();
        const std::vector<double> v = numbers(range->first);
        force_range = limited && v.size() == 2;
        if (force_range) out_.joints.push_back(JointForcePatch{static_cast<int>(j), model_.where(n), v[0], v[1]});
      }
      // through the actuators, the compensation differs from the passive one only by the clamp
      // of actuatorfrcrange, which it then shares with the actuator force
      const auto through_actuators = resolve(n, {"joint"}, "actuatorgravcomp");
      if (through_actuators && through_actuators->first == "true") {
        if (force_range) {
          untranslatable(n, "actuatorgravcomp",
                         "with the joint's actuatorfrcrange, the compensation and the actuator force are clamped "
                         "together, which idmpc does not model (without actuatorfrcrange it is the passive force)");
        } else {
          actuator_gravcomp_joints_.push_back(model_.where(n));
        }
      }
    }
  }

  void untranslatable(const Node* n, const std::string& name, const std::string& why) {
    const std::string item = n->tag() == name ? "element " + model_.where(n) + ": " + why
                                              : "attribute '" + name + "' (" + model_.where(n) + "): " + why;
    if (std::find(out_.untranslatable.begin(), out_.untranslatable.end(), item) == out_.untranslatable.end()) {
      out_.untranslatable.push_back(item);
    }
  }

  // what to do with each name of MuJoCo >= 2.3 that MuJoCo 2.2 rejects
  void scan_newer_names() {
    for (Node* n : all_) {
      const std::string tag = n->tag();
      if (const auto it = kNewerElements.find(tag); it != kNewerElements.end()) {
        untranslatable(n, tag, it->second);
        remove_element_.push_back(n);
        continue;
      }
      for (const tinyxml2::XMLAttribute* a = n->e->FirstAttribute(); a; a = a->Next()) {
        const std::string name = a->Name(), value = a->Value();
        if ((name == "kv" || name == "dampratio" || name == "inheritrange") && kServoShortcuts.count(tag)) {
          remove_attr_.emplace_back(n, name);  // translated in the compiled model
        } else if ((name == "actuatorfrcrange" || name == "actuatorfrclimited") && tag == "joint") {
          remove_attr_.emplace_back(n, name);  // translated in the compiled model
        } else if (name == "integrator" && value == "implicitfast") {
          set_attr_.push_back({n, name, "implicit"});
          out_.notices.push_back({"implicitfast as implicit", "integrator implicitfast replaced by implicit (" + model_.where(n) +
                                 "), a different integrator: MuJoCo 2.2 has no implicitfast, and implicit also "
                                 "keeps the Coriolis and centrifugal derivatives implicitfast leaves out"});
        } else if (name == "assetdir" && tag == "compiler") {
          for (const char* dir : {"meshdir", "texturedir"}) {
            if (!n->has(dir)) set_attr_.push_back({n, dir, value});
          }
          remove_attr_.emplace_back(n, name);
          out_.notices.push_back({"assetdir", "<compiler assetdir=\"" + value + "\"> given as meshdir and texturedir (" +
                                 model_.where(n) + ")"});
        } else if (kRenderOnlyAttributes.count(tag) && kRenderOnlyAttributes.at(tag).count(name)) {
          remove_attr_.emplace_back(n, name);
          if (name == "type" && value == "directional") set_attr_.push_back({n, "directional", "true"});
          render_only_[tag + " " + name] += 1;
        } else if (name == "actuatorgravcomp" && tag == "joint" && value == "true") {
          remove_attr_.emplace_back(n, name);  // decided per joint in plan_joints
        } else if (name == "gravcomp" && tag == "body" && body_id_.count(n) && std::atof(value.c_str()) != 0) {
          // kept in the compiled model as a custom numeric field (gravcomp.hpp)
          remove_attr_.emplace_back(n, name);
          out_.gravcomp.push_back(GravcompPatch{body_id_.at(n), model_.where(n), std::atof(value.c_str())});
        } else if (const auto it = kNewerAttributes.find(name); it != kNewerAttributes.end()) {
          const bool no_op = (name == "gravcomp" && std::atof(value.c_str()) == 0 && !trimmed(value).empty()) ||
                             ((name == "actuatorgravcomp" || name == "actearly") && value == "false") ||
                             (name == "eulerdamp" && value == "enable");
          remove_attr_.emplace_back(n, name);
          if (no_op) {
            out_.notices.push_back({"no-op values dropped", name + "=\"" + value + "\" dropped (" + model_.where(n) +
                                   "): MuJoCo 2.2 behaves so without it"});
          } else {
            untranslatable(n, name, it->second);
          }
        }
      }
      if (tag == "key") {
        for (const char* key : {"time", "qpos", "qvel", "act", "ctrl", "mpos", "mquat"}) {
          const std::string v = n->get(key);
          if (n->has(key) && trimmed(v) != v) {
            set_attr_.push_back({n, key, trimmed(v)});
            out_.notices.push_back({"keyframe blanks", std::string("keyframe ") + key + " trimmed of surrounding blanks (" +
                                   model_.where(n) + "): MuJoCo 2.2 reads a trailing blank as a missing number"});
          }
        }
      }
    }
    if (!render_only_.empty()) {
      std::string list;
      for (const auto& [attribute, count] : render_only_) {
        list += (list.empty() ? "" : ", ") + attribute + (count > 1 ? " (" + std::to_string(count) + "×)" : "");
      }
      out_.notices.push_back({"render-only attributes dropped",
                              "dropped what MuJoCo 2.2 does not have and only rendering uses: " + list +
                                  " (a light's type directional kept as directional=\"true\")"});
    }
  }

  void edit_text() {
    if (set_autolimits_) {
      if (!compilers_.empty()) {
        compilers_.front()->e->SetAttribute("autolimits", "true");
        compilers_.front()->src->changed = true;
      } else {
        XMLElement* root = model_.root()->e;
        XMLElement* compiler = root->GetDocument()->NewElement("compiler");
        compiler->SetAttribute("autolimits", "true");
        root->InsertFirstChild(compiler);
        model_.root()->src->changed = true;
      }
    }
    for (const Assignment& s : set_attr_) {
      s.node->e->SetAttribute(s.name.c_str(), s.value.c_str());
      s.node->src->changed = true;
    }
    for (const auto& [n, name] : remove_attr_) {
      n->e->DeleteAttribute(name.c_str());
      n->src->changed = true;
    }
    // each element once, and none inside another that goes
    const std::set<const Node*> removed(remove_element_.begin(), remove_element_.end());
    std::set<const Node*> done;
    for (Node* n : remove_element_) {
      bool inside = !done.insert(n).second;
      for (const Node* p = n->parent; p && !inside; p = p->parent) inside = removed.count(p) > 0;
      if (inside) continue;
      if (XMLElement* parent = n->e->Parent() ? n->e->Parent()->ToElement() : nullptr) {
        parent->DeleteChild(n->e);
        n->src->changed = true;
      }
    }
    if (!out_.gravcomp.empty()) add_gravcomp_field();
    for (const auto& src : model_.sources()) {
      if (src->changed || welded_) out_.files.emplace_back(src->path, LinePrinter().print(*src->doc));
    }
  }

  // each body's gravcomp as the custom numeric field gravcomp.hpp reads, and one notice
  void add_gravcomp_field() {
    std::vector<double> value(static_cast<std::size_t>(next_body_), 0.0);
    for (const GravcompPatch& p : out_.gravcomp) value[static_cast<std::size_t>(p.body)] = p.value;
    std::ostringstream data;
    data.precision(17);
    for (std::size_t b = 0; b < value.size(); ++b) data << (b ? " " : "") << value[b];
    XMLElement* root = model_.root()->e;
    XMLElement* custom = root->GetDocument()->NewElement("custom");
    XMLElement* numeric = root->GetDocument()->NewElement("numeric");
    numeric->SetAttribute("name", kGravcompField);
    numeric->SetAttribute("size", next_body_);
    numeric->SetAttribute("data", data.str().c_str());
    custom->InsertEndChild(numeric);
    root->InsertEndChild(custom);
    model_.root()->src->changed = true;
    const std::size_t count = out_.gravcomp.size();
    std::string text = "gravcomp on " + std::to_string(count) + (count == 1 ? " body (" : " bodies (") +
                       out_.gravcomp.front().where + (count > 1 ? ", …" : "") +
                       ") applied as MuJoCo >= 2.3 applies it, an upward passive force gravcomp·m·g at the centre of mass";
    if (!actuator_gravcomp_joints_.empty()) {
      text += "; actuatorgravcomp (" + actuator_gravcomp_joints_.front() +
              (actuator_gravcomp_joints_.size() > 1 ? ", …" : "") + ") is the same force without actuatorfrcrange";
    }
    out_.notices.push_back({"gravcomp", text});
  }

  struct Assignment {
    Node* node;
    std::string name, value;
  };

  MjcfTree& model_;
  Defaults defaults_;
  MjcfTranslation& out_;
  const Weld* weld_;
  bool welded_ = false;
  std::vector<Node*> all_, compilers_, actuators_, tendons_, joints_;
  std::map<const Node*, int> body_id_;
  std::map<int, Node*> body_node_;
  int next_body_ = 1;
  std::vector<std::string> actuator_gravcomp_joints_;  // where actuatorgravcomp is the passive force
  std::vector<Assignment> set_attr_;
  std::vector<std::pair<Node*, std::string>> remove_attr_;
  std::vector<Node*> remove_element_;
  std::map<std::string, int> render_only_;  ///< "<tag> <attribute>" dropped: how often
  bool set_autolimits_ = false;
};

// --------------------------------------------------------------------------------------------
// after compilation

std::string actuator_label(const mjModel* m, int u) {
  const char* name = mj_id2name(m, mjOBJ_ACTUATOR, u);
  return std::string("actuator '") + (name && name[0] ? name : "#" + std::to_string(u)) + "'";
}

std::string joint_label(const mjModel* m, int j) {
  const char* name = mj_id2name(m, mjOBJ_JOINT, j);
  return std::string("joint '") + (name && name[0] ? name : "#" + std::to_string(j)) + "'";
}

std::string range_text(double lo, double hi) { return "[" + number(lo) + ", " + number(hi) + "]"; }

}  // namespace


MjcfTranslation translate_mjcf(const std::string& path, const Weld* weld) {
  MjcfTranslation out;
  MjcfTree model(path);
  if (!model.ok()) {
    if (weld) throw std::invalid_argument("cannot weld joints of '" + path + "': it is no MJCF file idmpc can read");
    return out;
  }
  Translator(model, out, weld).run();
  return out;
}

JointForceRanges apply_translation(mjModel* m, const MjcfTranslation& t, std::vector<Translation>& notices,
                                   std::vector<std::string>& untranslatable) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  JointForceRanges ranges{std::vector<double>(m->njnt, -kInf), std::vector<double>(m->njnt, kInf)};
  if (t.actuators.empty() && t.joints.empty()) return ranges;
  const int nv = m->nv;
  // actuator moments at qpos0, as MuJoCo's compiler computes them
  mjData* d = mj_makeData(m);
  if (!d) throw std::runtime_error("MuJoCo could not allocate mjData");
  mju_copy(d->qpos, m->qpos0, m->nq);
  mj_kinematics(m, d);
  mj_comPos(m, d);
  mj_tendon(m, d);
  mj_transmission(m, d);
  const std::vector<mjtNum> moment(d->actuator_moment, d->actuator_moment + static_cast<std::size_t>(m->nu) * nv);
  mj_deleteData(d);

  for (const ActuatorPatch& p : t.actuators) {
    if (p.actuator >= m->nu) continue;
    const int u = p.actuator;
    const std::string label = actuator_label(m, u) + " (" + p.where + ")";
    if (p.inheritrange > 0) {
      const int type = m->actuator_trntype[u], id = m->actuator_trnid[2 * u];
      const mjtNum* range = nullptr;
      bool limited = false;
      if ((type == mjTRN_JOINT || type == mjTRN_JOINTINPARENT) &&
          (m->jnt_type[id] == mjJNT_HINGE || m->jnt_type[id] == mjJNT_SLIDE)) {
        range = m->jnt_range + 2 * id;
        limited = m->jnt_limited[id];
      } else if (type == mjTRN_TENDON) {
        range = m->tendon_range + 2 * id;
        limited = m->tendon_limited[id];
      }
      if (!range || !limited) {
        untranslatable.push_back("attribute 'inheritrange' (" + p.where +
                                 "): its target is no hinge, slide or tendon with a range (MuJoCo >= 2.3 refuses "
                                 "it too)");
      } else {
        const double centre = 0.5 * (range[1] + range[0]), radius = 0.5 * (range[1] - range[0]) * p.inheritrange;
        mjtNum* target = (p.activation ? m->actuator_actrange : m->actuator_ctrlrange) + 2 * u;
        target[0] = centre - radius;
        target[1] = centre + radius;
        (p.activation ? m->actuator_actlimited : m->actuator_ctrllimited)[u] = 1;
        notices.push_back({"inheritrange", label + ": inheritrange " + number(p.inheritrange) + " gives " +
                                               (p.activation ? "actrange " : "ctrlrange ") +
                                               range_text(target[0], target[1])});
      }
    }
    if (p.set_bias) {
      mjtNum* bias = m->actuator_biasprm + u * mjNBIAS;
      const double kp = m->actuator_gainprm[u * mjNGAIN];
      if (p.bias < 0) {
        bias[2] = p.bias;
        notices.push_back({"kv", label + ": " + p.bias_source + " gives biasprm[2] = " + number(bias[2])});
      } else {
        // MuJoCo >= 2.3: damping = dampratio·2·√(kp·m), m the inertia reflected through the
        // transmission at qpos0
        double mass = 0;
        for (int j = 0; j < nv; ++j) {
          const double trn = std::abs(moment[static_cast<std::size_t>(u) * nv + j]);
          if (trn * trn > mjMINVAL) mass += m->dof_M0[j] / (trn * trn);
        }
        bias[2] = -p.bias * 2 * std::sqrt(kp * mass);
        notices.push_back({"dampratio", label + ": " + p.bias_source + " gives kv " + number(-bias[2]) +
                                            " (biasprm[2], from the inertia " + number(mass) + " at qpos0)"});
      }
    }
  }

  for (const JointForcePatch& p : t.joints) {
    if (p.joint >= m->njnt) continue;
    const int j = p.joint;
    const std::string label = joint_label(m, j) + " (" + p.where + ")";
    if (!(p.lower <= p.upper)) {
      untranslatable.push_back("attribute 'actuatorfrcrange' (" + p.where + "): the range " +
                               range_text(p.lower, p.upper) + " is empty");
      continue;
    }
    const int dof = m->jnt_dofadr[j];
    std::vector<int> drivers;
    bool other = false;
    for (int u = 0; u < m->nu; ++u) {
      const int type = m->actuator_trntype[u];
      if (type == mjTRN_JOINT || type == mjTRN_JOINTINPARENT) {
        if (m->actuator_trnid[2 * u] == j) drivers.push_back(u);
      } else if (type != mjTRN_TENDON || moment[static_cast<std::size_t>(u) * nv + dof] != 0) {
        // tendons through the joint, and transmissions whose moment depends on the state
        drivers.push_back(u);
        other = true;
      }
    }
    if (drivers.empty()) {
      ranges.lower[j] = p.lower;
      ranges.upper[j] = p.upper;
      notices.push_back({"actuatorfrcrange", label + ": actuatorfrcrange " + range_text(p.lower, p.upper) +
                                                 " kept as the joint's torque range (no actuator drives it)"});
      continue;
    }
    const int u = drivers.front();
    const double gear = m->actuator_gear[6 * u];
    if (drivers.size() > 1 || other || !(std::abs(gear) > 0)) {
      std::string names;
      for (int k : drivers) names += (names.empty() ? "" : ", ") + actuator_label(m, k);
      untranslatable.push_back("attribute 'actuatorfrcrange' (" + p.where +
                               "): it clamps the sum of the forces of " + names +
                               ", and MuJoCo 2.2 can only clamp each joint actuator's own force");
      continue;
    }
    double lo = std::min(p.lower / gear, p.upper / gear), hi = std::max(p.lower / gear, p.upper / gear);
    mjtNum* fr = m->actuator_forcerange + 2 * u;
    bool within_own = false;  // narrowed by the actuator's own forcerange
    if (m->actuator_forcelimited[u]) {
      within_own = fr[0] > lo || fr[1] < hi;
      lo = std::max(lo, fr[0]);
      hi = std::min(hi, fr[1]);
    }
    if (!(lo <= hi)) {
      untranslatable.push_back("attribute 'actuatorfrcrange' (" + p.where + "): " +
                               range_text(p.lower, p.upper) + " and the forcerange of " + actuator_label(m, u) +
                               " do not overlap");
      continue;
    }
    fr[0] = lo;
    fr[1] = hi;
    m->actuator_forcelimited[u] = 1;
    notices.push_back({"actuatorfrcrange", label + ": actuatorfrcrange " + range_text(p.lower, p.upper) +
                                               " becomes forcerange " + range_text(lo, hi) +
                                               (within_own ? " (its part within the actuator's own)" : "") + " of " +
                                               actuator_label(m, u) + ", its only actuator (gear " + number(gear) + ")"});
  }
  return ranges;
}

}  // namespace idmpc::mj
