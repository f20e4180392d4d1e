#pragma once
// The twin's contact check: every contact between the rig's moving side (every geom under the
// first arm joint's body: the links, the camera bracket and housing; the free rig's camera) and
// anything else solid in the rig (table, pedestal, arm base, turntable housing, platter, the
// object, the calibration sphere), and between the object (and calibration sphere) turning on
// the turntable and the rig's fixed parts (every solid geom welded to the world: the table, the
// pedestal, the arm's base; an object too wide for the rig jams against them), found on a copy of
// the rig's model of its own, so that the check neither depends on nor changes the physics (whose
// contact filtering, flags and margins stay as the rig file says).
//
// The object counts by its convex hull: MuJoCo 2.2.2 collides a mesh as its convex hull, so an
// arm reaching into a concavity of the object (between a mug's handle and its body) is reported
// as touching it. A conservative stand-in for the mesh: never a contact missed, possibly one
// reported that the real object would not have.
//
// A contact *event* is the onset of a pair (a moving body, an other geom) touching: penetrating,
// distance < 0. It counts once until the pair separates, which is when the two are more than
// kSeparatedM apart (so that a pair held in contact whose depth jitters about zero counts once).
// The states between two checks are swept: the joint-space line from the state last checked to
// the new one is checked at so many points that no point of the moving side (or of the turntable
// and what it carries) moves more than kMaxSweepStepM from one to the next.
#include <mujoco/mujoco.h>

#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace pbnbv::twin {

// The sweep's spacing: no point of the rig's moving parts moves further between two checked states.
inline constexpr double kMaxSweepStepM = 2e-3;
// A pair in contact separates when its distance exceeds this.
inline constexpr double kSeparatedM = 1e-3;

// One contact event.
struct RigContact {
  std::string moving;       // the moving side's body ("link_6", "camera_optical", "object")
  std::string other;        // the other geom ("platter", "object", "table")
  double depth_m = 0;       // penetration when found
  double rig_time_s = 0;    // rig time when found
  int64_t command_seq = -1; // the arm command being executed (-1: none yet)
  // "link_6 / platter, 3.2 mm deep, at rig time 12.345 s, during command 17"
  std::string text() const;
};

// What the contact check costs: checked states, and the wall time spent in them.
struct ContactCheckCost {
  int64_t calls = 0;       // check() calls that checked at least one state
  int64_t states = 0;      // states checked (kinematics + collision)
  double seconds = 0;      // wall time in them
};

class ContactMonitor {
 public:
  // A copy of `model` (not kept) in which only the pairs (moving side, other) collide: the moving
  // side is every geom in the subtree of the body of joint `first_joint`; the other side every
  // geom outside it that collides in the rig (contype or conaffinity set) and the geoms the twin
  // inserts, "object" and "calibration_sphere", whatever their flags. Parent-child filtering is
  // off (the first link against the arm's base is checked too); margins are kSeparatedM.
  // `qpos` is the rig's state to start from, checked at once (initial_contacts: a rig that starts
  // in contact reports it). Throws std::runtime_error naming a joint that is missing.
  ContactMonitor(const mjModel* model, const std::string& first_joint, const double* qpos);
  ~ContactMonitor();
  ContactMonitor(const ContactMonitor&) = delete;
  ContactMonitor& operator=(const ContactMonitor&) = delete;

  // Checks the states from the one last checked to `qpos` (model->nq values): swept when `sweep`
  // (the joint-space line between them, kMaxSweepStepM apart), else `qpos` alone (a rig that
  // teleports). A state that moved no point by more than a micrometre is not checked again.
  // Returns the contact events that began, in the order found.
  std::vector<RigContact> check(const double* qpos, bool sweep, double rig_time_s, int64_t command_seq);

  // The contact events so far (the first state's included).
  int64_t events() const { return events_; }
  // The events of the first state (the constructor's `qpos`).
  const std::vector<RigContact>& initial_contacts() const { return initial_; }
  // The pairs in contact at the last state checked (touched and not yet separated), as
  // "moving / other".
  std::vector<std::string> touching() const;
  // The most any point of the rig moves between the last state checked and `qpos` (a bound:
  // joint by joint, the angle times the reach of what it carries).
  double motion_bound_m(const double* qpos) const;
  const ContactCheckCost& cost() const { return cost_; }
  // The geoms on each side (tests, and the twin's log).
  const std::vector<int>& moving_geoms() const { return moving_; }
  const std::vector<int>& other_geoms() const { return other_; }

 private:
  // Kinematics and collision at `qpos`; the events that began there.
  std::vector<RigContact> check_state(const double* qpos, double rig_time_s, int64_t command_seq);

  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  std::vector<int> moving_, other_;         // geom ids
  std::vector<char> is_moving_, is_other_;  // per geom
  std::vector<char> is_turning_, is_fixed_; // per geom: the object on the turntable; welded to the world
  // Per joint (hinge or slide): the checked geoms it carries (its body's subtree).
  std::vector<std::vector<int>> carried_;
  std::vector<double> last_qpos_;           // the state last checked
  std::set<std::pair<int, int>> touching_;  // (moving body, or -1 - turning geom; other geom) within
                                            // kSeparatedM after touching
  int64_t events_ = 0;
  std::vector<RigContact> initial_;
  ContactCheckCost cost_;
};

}  // namespace pbnbv::twin
