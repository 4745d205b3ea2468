#pragma once
// A comedi rig with every kind of trigger and a [recording] table, for the rig-file tests
// of triggers (test_rig_file.cpp) and the trigger options read from it (test_trigger.cpp).
// Line numbers in the comments are the ones error messages give.
#include <string>

namespace doorbench::testing {

inline const std::string kTriggerRig =
    "[bench]\n"                          // 1
    "name = \"b\"\n"                     // 2
    "[daq]\n"                            // 3
    "backend = \"comedi\"\n"             // 4
    "device = \"/dev/comedi0\"\n"        // 5
    "start_trigger = \"door_switch\"\n"  // 6
    "[[channels]]\n"                     // 7
    "name = \"force\"\n"                 // 8
    "sensor = \"load_cell\"\n"           // 9
    "serial = \"LC-1\"\n"                // 10
    "backend = \"comedi\"\n"             // 11
    "address = \"0/0\"\n"                // 12
    "calibration = \"nominal\"\n"        // 13
    "unit = \"N\"\n"                     // 14
    "[[channels]]\n"                     // 15
    "name = \"rate\"\n"                  // 16
    "sensor = \"gyroscope\"\n"           // 17
    "serial = \"G-1\"\n"                 // 18
    "backend = \"comedi\"\n"             // 19
    "address = \"0/1\"\n"                // 20
    "calibration = \"nominal\"\n"        // 21
    "unit = \"rad/s\"\n"                 // 22
    "[[triggers]]\n"                     // 23
    "name = \"door_switch\"\n"           // 24
    "kind = \"external\"\n"              // 25
    "source = \"PFI0\"\n"                // 26
    "[[triggers]]\n"                     // 27
    "name = \"push\"\n"                  // 28
    "kind = \"level\"\n"                 // 29
    "channel = \"force\"\n"              // 30
    "level = 2.0\n"                      // 31
    "hysteresis = 0.5\n"                 // 32
    "unit = \"N\"\n"                     // 33
    "[[triggers]]\n"                     // 34
    "name = \"release\"\n"               // 35
    "kind = \"level\"\n"                 // 36
    "channel = \"force\"\n"              // 37
    "direction = \"falling\"\n"          // 38
    "level = 0.5\n"                      // 39
    "hold_s = 1.5\n"                     // 40
    "[[triggers]]\n"                     // 41
    "name = \"moving\"\n"                // 42
    "kind = \"level\"\n"                 // 43
    "channel = \"rate\"\n"               // 44
    "level = 0.2\n"                      // 45
    "hysteresis = 0.05\n"                // 46
    "absolute = true\n"                  // 47
    "[[triggers]]\n"                     // 48
    "name = \"enter\"\n"                 // 49
    "kind = \"manual\"\n"                // 50
    "[recording]\n"                      // 51
    "start = \"push\"\n"                 // 52
    "stop = \"release\"\n"               // 53
    "duration_s = 30\n"                  // 54
    "pre_trigger_s = 2\n"                // 55
    "strokes = \"moving\"\n";            // 56

}  // namespace doorbench::testing
