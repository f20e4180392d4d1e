// The RTDE codec (rtde.hpp) against bytes computed by hand, and the UR arm's plain functions
// (ur_arm.hpp): recipes, state, registers, faults, the reading and the program.
#include "driver/rtde.hpp"

#include <gtest/gtest.h>

#include "driver/ur_arm.hpp"

namespace pbnbv::driver::rtde {
namespace {

using Bytes = std::vector<uint8_t>;

// The message of the RtdeError `f` throws ("" when it throws none).
template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const RtdeError& e) {
    return e.what();
  }
  return "";
}

TEST(Rtde, RequestsAreTheBytesOfTheProtocol) {
  EXPECT_EQ(encode(request_protocol_version()), (Bytes{0x00, 0x05, 0x56, 0x00, 0x02}));
  EXPECT_EQ(encode(get_urcontrol_version()), (Bytes{0x00, 0x03, 0x76}));
  EXPECT_EQ(encode(start()), (Bytes{0x00, 0x03, 0x53}));
  EXPECT_EQ(encode(pause()), (Bytes{0x00, 0x03, 0x50}));
  // 3 + 8 + 18 = 29 bytes: 125 Hz = 0x405F400000000000, then the names.
  EXPECT_EQ(encode(setup_outputs(125, {"timestamp", "actual_q"})),
            (Bytes{0x00, 0x1d, 0x4f, 0x40, 0x5f, 0x40, 0, 0, 0, 0, 0, 't', 'i', 'm', 'e', 's', 't', 'a', 'm', 'p', ',',
                   'a', 'c', 't', 'u', 'a', 'l', '_', 'q'}));
  EXPECT_EQ(encode(setup_inputs({"input_int_register_0"})).size(), 3u + 20u);
  EXPECT_THROW(setup_inputs({}), std::invalid_argument);
  EXPECT_THROW(setup_inputs({"a,b"}), std::invalid_argument);
}

TEST(Rtde, DataPackagesRoundTripByTheirRecipe) {
  Data d;
  d.recipe_id = 2;
  d.values = {scalar(Type::kInt32, -2), scalar(Type::kDouble, 1.0), scalar(Type::kUint32, 7), scalar(Type::kBool, 1)};
  const Bytes bytes = encode(data_package(d));
  // 3 header + 1 id + 4 + 8 + 4 + 1
  EXPECT_EQ(bytes, (Bytes{0x00, 0x15, 0x55, 0x02, 0xff, 0xff, 0xff, 0xfe, 0x3f, 0xf0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 7, 1}));
  const std::vector<Type> recipe = {Type::kInt32, Type::kDouble, Type::kUint32, Type::kBool};
  const Data back = parse_data_package(decode(bytes), 2, recipe);
  ASSERT_EQ(back.values.size(), 4u);
  EXPECT_EQ(back.values[0].number, -2);
  EXPECT_EQ(back.values[1].number, 1.0);
  EXPECT_EQ(back.values[2].number, 7);
  EXPECT_EQ(back.values[3].number, 1);
  EXPECT_NE(error_of([&] { parse_data_package(decode(bytes), 3, recipe); }).find("recipe id 2, expected 3"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parse_data_package(decode(bytes), 2, {Type::kInt32}); })
                .find("'U' (data package): 18 payload bytes, recipe 2 makes 5"),
            std::string::npos);
  d.values[0] = scalar(Type::kInt32, 3e9);
  EXPECT_THROW(data_package(d), std::invalid_argument);
}

TEST(Rtde, AnswersAreParsedAndCheckedByType) {
  EXPECT_TRUE(parse_accepted(decode({0x00, 0x04, 0x56, 0x01}), kRequestProtocolVersion));
  EXPECT_FALSE(parse_accepted(decode({0x00, 0x04, 0x53, 0x00}), kStart));
  EXPECT_EQ(error_of([] { parse_accepted(decode({0x00, 0x04, 0x53, 0x01}), kPause); }),
            "expected 'P' (pause), got 'S' (start)");
  EXPECT_EQ(error_of([] { parse_accepted(decode({0x00, 0x03, 0x56}), kRequestProtocolVersion); }),
            "'V' (request protocol version): payload of 0 bytes ends before its uint8 (byte 0)");
  EXPECT_NE(error_of([] { parse_accepted(decode({0x00, 0x05, 0x56, 1, 1}), kRequestProtocolVersion); })
                .find("1 unexpected bytes"),
            std::string::npos);
  const UrControlVersion v = parse_urcontrol_version(urcontrol_version_answer({5, 11, 2, 1234}));
  EXPECT_EQ(v.major, 5u);
  EXPECT_EQ(v.build, 1234u);

  const SetupAnswer a = parse_setup_answer(setup_answer(kSetupOutputs, {1, {"DOUBLE", "VECTOR6D"}}), kSetupOutputs);
  EXPECT_EQ(a.recipe_id, 1);
  EXPECT_EQ(recipe_types(a, {"timestamp", "actual_q"}), (std::vector<Type>{Type::kDouble, Type::kVector6d}));
  EXPECT_EQ(error_of([] { recipe_types({1, {"DOUBLE", "NOT_FOUND"}}, {"timestamp", "actual_qq"}); }),
            "the controller does not know the variable actual_qq (NOT_FOUND)");
  EXPECT_EQ(error_of([] { recipe_types({1, {"IN_USE"}}, {"input_int_register_0"}); }),
            "the variable input_int_register_0 is in use by another RTDE client or program (IN_USE)");
  EXPECT_EQ(error_of([] { recipe_types({1, {"INT32"}}, {"timestamp"}, {Type::kDouble}); }),
            "the variable timestamp is INT32, expected DOUBLE");
  EXPECT_NE(error_of([] { recipe_types({1, {"INT32"}}, {"a", "b"}); }).find("1 types for 2 variables"), std::string::npos);

  const TextMessage m = parse_text_message(text_message({"hello", "pbnbv", 2}));
  EXPECT_EQ(m.message, "hello");
  EXPECT_EQ(m.source, "pbnbv");
  EXPECT_EQ(m.level, 2);
  EXPECT_NE(error_of([] { parse_text_message(decode({0x00, 0x06, 0x4d, 9, 'h', 'i'})); }).find("ends before its message"),
            std::string::npos);

  EXPECT_EQ(parse_protocol_version_request(request_protocol_version()), 2);
  const SetupRequest s = parse_setup_request(setup_outputs(500, {"timestamp", "actual_q"}));
  EXPECT_EQ(s.frequency_hz, 500);
  EXPECT_EQ(s.names, (std::vector<std::string>{"timestamp", "actual_q"}));
  EXPECT_NE(error_of([] { parse_setup_request(setup_outputs(1000, {"x"})); }).find("frequency 1000"), std::string::npos);
}

TEST(Rtde, TheFramerSplitsAStreamAndRefusesBadSizes) {
  Framer f;
  Bytes stream = encode(request_protocol_version());
  const Bytes second = encode(start());
  stream.insert(stream.end(), second.begin(), second.end());
  f.feed(stream.data(), 4);  // a package cut in two
  EXPECT_FALSE(f.next());
  f.feed(stream.data() + 4, stream.size() - 4);
  EXPECT_EQ(f.next()->type, kRequestProtocolVersion);
  EXPECT_EQ(f.next()->type, kStart);
  EXPECT_FALSE(f.next());

  Framer small;
  const Bytes two = {0x00, 0x02, 0x55};
  small.feed(two.data(), two.size());
  EXPECT_EQ(error_of([&] { small.next(); }), "'U' (data package): size field 2 outside 3..4096");
  Framer big;
  const Bytes huge = {0xff, 0xff, 0x4d};
  big.feed(huge.data(), huge.size());
  EXPECT_EQ(error_of([&] { big.next(); }), "'M' (text message): size field 65535 outside 3..4096");
  EXPECT_EQ(error_of([] { decode({0x00, 0x09, 0x56, 0, 2}); }), "'V' (request protocol version): size field 9 but 5 bytes");
  EXPECT_EQ(error_of([] { decode({0x00}); }), "package of 1 bytes is shorter than its 3-byte header");
  EXPECT_EQ(error_of([] { encode(Package{kTextMessage, Bytes(5000, 0)}); }),
            "'M' (text message): 5003 bytes exceed the limit of 4096");
  EXPECT_EQ(type_label(0x42), "package type 66 (unknown)");
}

}  // namespace
}  // namespace pbnbv::driver::rtde

namespace pbnbv::driver::ur {
namespace {

TEST(UrArm, StateAndRegistersRoundTripThroughTheRecipes) {
  State s;
  s.timestamp_s = 12.5;
  s.q = {0.1, -1, 2, 0, 0.5, 3};
  s.target_q = s.q;
  s.robot_mode = kRobotModeRunning;
  s.safety_mode = kSafetyModeNormal;
  s.runtime_state = kRuntimePlaying;
  s.echo = 9;
  const rtde::Package p = rtde::data_package(data_of(1, s));
  const State back = state_of(rtde::parse_data_package(p, 1, output_types()));
  EXPECT_EQ(back.q, s.q);
  EXPECT_EQ(back.echo, 9);
  EXPECT_EQ(back.timestamp_s, 12.5);
  EXPECT_EQ(drive_fault(back), "");
  // 1 id + DOUBLE + 3 VECTOR6D + INT32 INT32 UINT32 INT32
  EXPECT_EQ(p.payload.size(), 1u + 8 + 3 * 48 + 16);

  Registers r{{1, 2, 3, 4, 5, 6}, 0.5, 4, true};
  const Registers rb = registers_of(rtde::parse_data_package(rtde::data_package(data_of(2, r)), 2, input_types()));
  EXPECT_EQ(rb.target, r.target);
  EXPECT_EQ(rb.speed_scale, 0.5);
  EXPECT_EQ(rb.number, 4);
  EXPECT_TRUE(rb.stop);
  EXPECT_THROW(state_of(rtde::parse_data_package(rtde::data_package(data_of(2, r)), 2, input_types())), rtde::RtdeError);
}

TEST(UrArm, DriveFaultsNameTheModeAndWhatToDo) {
  State s;
  s.robot_mode = kRobotModeRunning;
  s.runtime_state = kRuntimePlaying;
  s.safety_mode = kSafetyModeProtectiveStop;
  EXPECT_EQ(drive_fault(s), "protective stop (safety mode 3): clear it on the teach pendant");
  s.safety_mode = 7;
  EXPECT_EQ(drive_fault(s), "robot emergency stop (safety mode 7): release the emergency stop and reset the robot on the teach pendant");
  s.safety_mode = kSafetyModeReduced;
  EXPECT_EQ(drive_fault(s), "");
  s.robot_mode = 5;
  EXPECT_NE(drive_fault(s).find("robot mode 5, not running"), std::string::npos);
  s.robot_mode = kRobotModeRunning;
  s.runtime_state = 1;
  EXPECT_NE(drive_fault(s).find("not playing (runtime state 1)"), std::string::npos);
}

TEST(UrArm, TheReadingFollowsTheEcho) {
  const std::vector<std::string> names = {"a", "b", "c", "d", "e", "f"};
  State s;
  Sent sent;
  EXPECT_EQ(reading_of(s, sent, names).motion, Motion::kIdle);
  sent = {3, 41, false, {0.5, 0, 0, 0, 0, 0}};
  s.echo = 2;  // the program has not started it yet
  ArmReading r = reading_of(s, sent, names);
  EXPECT_EQ(r.motion, Motion::kMoving);
  EXPECT_EQ(r.command_seq, -1);
  EXPECT_EQ(r.commanded_rad[0], 0.5);
  s.echo = 3;
  s.qd[0] = 0.3;
  s.q[0] = 0.2;
  r = reading_of(s, sent, names);
  EXPECT_EQ(r.command_seq, 41);
  EXPECT_EQ(r.motion, Motion::kMoving);
  s.qd[0] = 0;
  s.q[0] = s.target_q[0] = 0.5;
  EXPECT_EQ(reading_of(s, sent, names).motion, Motion::kSettled);
  s.q[0] = 0.3;  // still, short of the target: not settled
  EXPECT_EQ(reading_of(s, sent, names).motion, Motion::kMoving);
  sent.hold = true;
  EXPECT_EQ(reading_of(s, sent, names).motion, Motion::kSettled);
}

TEST(UrArm, TheProgramCarriesTheSpeedsAndIsRecognised) {
  const std::string p = program(1.5, 6);
  EXPECT_EQ(p.rfind(kProgramName, 0), 0u);
  EXPECT_NE(p.find("read_input_float_register(6) * 1.5"), std::string::npos) << p;
  EXPECT_NE(p.find("read_input_float_register(6) * 6"), std::string::npos) << p;
  EXPECT_NE(p.find("stopj(6)"), std::string::npos) << p;
  EXPECT_EQ(p.find("SPEED"), std::string::npos);
  EXPECT_EQ(p.back(), '\n');
  EXPECT_TRUE(is_program(p));
  EXPECT_FALSE(is_program("def other():\n  movej([0,0,0,0,0,0])\nend\n"));
  EXPECT_FALSE(is_program(p.substr(0, p.size() - 4)));
  EXPECT_THROW(program(0, 1), std::invalid_argument);
}

}  // namespace
}  // namespace pbnbv::driver::ur
