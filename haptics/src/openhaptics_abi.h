// The slice of the OpenHaptics device API (HDAPI, libHD) that PhantomDevice binds at run time
// with dlopen/dlsym: the scalar types, the error record, the enum values it passes and the
// function-pointer types of the entry points it resolves. Written from the interface facts in
// shared/reference/haptic-devices.md §1.4 (no vendor header is included or needed). The fake
// libHD of the tests (tests/fake_hd) exports its functions with exactly these types.
#pragma once

#include <climits>
#include <cstdint>

// The vendor declares its entry points and callbacks stdcall on Linux; x86-64 compilers ignore
// that, i386 ones do not.
#if defined(__i386__)
#define SULCUS_HD_CALL __attribute__((stdcall))
#else
#define SULCUS_HD_CALL
#endif

namespace sulcus::hd {

using HDboolean = unsigned char;  // a byte, not an int
using HDint = int;
using HDushort = unsigned short;
using HDulong = unsigned long;
using HDdouble = double;
using HDerror = unsigned int;
using HDenum = unsigned int;
using HDstring = const char*;
using HHD = unsigned int;                  // device handle
using HDCallbackCode = unsigned int;
using HDSchedulerHandle = unsigned long;   // 64 bits on LP64

// Returned by value from hdGetError().
struct HDErrorInfo {
    HDerror errorCode;
    int internalErrorCode;
    HHD hHD;
};
static_assert(sizeof(HDErrorInfo) == 12, "HDErrorInfo is three 32-bit fields");

using HDSchedulerCallback = HDCallbackCode(SULCUS_HD_CALL*)(void* user_data);

// Error codes (hdGetError().errorCode).
inline constexpr HDerror HD_SUCCESS = 0x0000;
inline constexpr HDerror HD_INVALID_ENUM = 0x0100;
inline constexpr HDerror HD_INVALID_VALUE = 0x0101;
inline constexpr HDerror HD_INVALID_OPERATION = 0x0102;
inline constexpr HDerror HD_INVALID_INPUT_TYPE = 0x0103;
inline constexpr HDerror HD_BAD_HANDLE = 0x0104;
inline constexpr HDerror HD_WARM_MOTORS = 0x0200;
inline constexpr HDerror HD_EXCEEDED_MAX_FORCE = 0x0201;
inline constexpr HDerror HD_EXCEEDED_MAX_FORCE_IMPULSE = 0x0202;
inline constexpr HDerror HD_EXCEEDED_MAX_VELOCITY = 0x0203;
inline constexpr HDerror HD_FORCE_ERROR = 0x0204;
inline constexpr HDerror HD_DEVICE_FAULT = 0x0300;
inline constexpr HDerror HD_DEVICE_ALREADY_INITIATED = 0x0301;
inline constexpr HDerror HD_COMM_ERROR = 0x0302;
inline constexpr HDerror HD_COMM_CONFIG_ERROR = 0x0303;
inline constexpr HDerror HD_TIMER_ERROR = 0x0304;
inline constexpr HDerror HD_ILLEGAL_BEGIN = 0x0400;
inline constexpr HDerror HD_ILLEGAL_END = 0x0401;
inline constexpr HDerror HD_FRAME_ERROR = 0x0402;
inline constexpr HDerror HD_INVALID_PRIORITY = 0x0500;
inline constexpr HDerror HD_SCHEDULER_FULL = 0x0501;
inline constexpr HDerror HD_INVALID_LICENSE = 0x0600;

// State queried each frame.
inline constexpr HDenum HD_CURRENT_BUTTONS = 0x2000;    // 1 int, bit i = button i+1
inline constexpr HDenum HD_CURRENT_VELOCITY = 0x2051;   // 3 doubles, mm/s
inline constexpr HDenum HD_CURRENT_TRANSFORM = 0x2052;  // 16 doubles, column-major, translation [12..14] mm

// Identity and hardware figures queried at start.
inline constexpr HDenum HD_DEVICE_MODEL_TYPE = 0x2501;            // string
inline constexpr HDenum HD_USABLE_WORKSPACE_DIMENSIONS = 0x2551;  // 6 doubles: min x,y,z, max x,y,z (mm)
inline constexpr HDenum HD_INPUT_DOF = 0x2553;                    // 1 int
inline constexpr HDenum HD_OUTPUT_DOF = 0x2554;                   // 1 int
inline constexpr HDenum HD_CALIBRATION_STYLE = 0x2555;            // 1 int, bit set of supported styles
inline constexpr HDenum HD_NOMINAL_MAX_STIFFNESS = 0x2602;        // 1 double, N/mm
inline constexpr HDenum HD_NOMINAL_MAX_FORCE = 0x2603;            // 1 double, N
inline constexpr HDenum HD_NOMINAL_MAX_CONTINUOUS_FORCE = 0x2604; // 1 double, N

// Output set each frame.
inline constexpr HDenum HD_CURRENT_FORCE = 0x2700;   // 3 doubles, N
inline constexpr HDenum HD_CURRENT_TORQUE = 0x2701;  // 3 doubles, mN·m (deprecated by the vendor)

// Capabilities for hdEnable.
inline constexpr HDenum HD_FORCE_OUTPUT = 0x4000;
inline constexpr HDenum HD_MAX_FORCE_CLAMPING = 0x4001;
inline constexpr HDenum HD_FORCE_RAMPING = 0x4002;
inline constexpr HDenum HD_SOFTWARE_FORCE_LIMIT = 0x4003;

// Calibration status (hdCheckCalibration) and styles (hdUpdateCalibration, HD_CALIBRATION_STYLE).
inline constexpr HDenum HD_CALIBRATION_OK = 0x5000;
inline constexpr HDenum HD_CALIBRATION_NEEDS_UPDATE = 0x5001;
inline constexpr HDenum HD_CALIBRATION_NEEDS_MANUAL_INPUT = 0x5002;
inline constexpr HDenum HD_CALIBRATION_ENCODER_RESET = 1u << 0;
inline constexpr HDenum HD_CALIBRATION_AUTO = 1u << 1;
inline constexpr HDenum HD_CALIBRATION_INKWELL = 1u << 2;

// Scheduler.
inline constexpr HDCallbackCode HD_CALLBACK_DONE = 0;
inline constexpr HDCallbackCode HD_CALLBACK_CONTINUE = 1;
inline constexpr HDushort HD_MAX_SCHEDULER_PRIORITY = USHRT_MAX;
inline constexpr HDushort HD_MIN_SCHEDULER_PRIORITY = 0;

inline constexpr HHD HD_INVALID_HANDLE = 0xFFFFFFFFu;

// Entry points (names as exported by libHD).
using InitDeviceFn = HHD(SULCUS_HD_CALL*)(HDstring config_name);  // null: the default device
using HandleFn = void(SULCUS_HD_CALL*)(HHD);                      // hdMakeCurrentDevice, hdDisableDevice, hdBeginFrame, hdEndFrame
using GetCurrentDeviceFn = HHD(SULCUS_HD_CALL*)();
using GetErrorFn = HDErrorInfo(SULCUS_HD_CALL*)();
using GetErrorStringFn = HDstring(SULCUS_HD_CALL*)(HDerror);
using EnumFn = void(SULCUS_HD_CALL*)(HDenum);                     // hdEnable, hdDisable, hdUpdateCalibration
using GetIntegervFn = void(SULCUS_HD_CALL*)(HDenum, HDint*);
using GetDoublevFn = void(SULCUS_HD_CALL*)(HDenum, HDdouble*);
using GetStringFn = HDstring(SULCUS_HD_CALL*)(HDenum);
using SetDoublevFn = void(SULCUS_HD_CALL*)(HDenum, const HDdouble*);
using CheckCalibrationFn = HDenum(SULCUS_HD_CALL*)();
using VoidFn = void(SULCUS_HD_CALL*)();                          // hdStartScheduler, hdStopScheduler
using ScheduleAsynchronousFn = HDSchedulerHandle(SULCUS_HD_CALL*)(HDSchedulerCallback, void*, HDushort priority);
using UnscheduleFn = void(SULCUS_HD_CALL*)(HDSchedulerHandle);

}  // namespace sulcus::hd
