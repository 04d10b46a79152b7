// The test-only controls of the fake libHD (tests/fake_hd/fake_hd.cpp). The fake exports them
// with C linkage beside the HDAPI entry points; a test reaches them with dlsym on the same
// library PhantomDevice loads, so both see one simulated device.
#pragma once

extern "C" {

// What the fake saw and did, copied out in one call.
struct FakeHdState {
    int initialized;            // hdInitDevice succeeded and hdDisableDevice not called since
    int force_output;           // HD_FORCE_OUTPUT enabled
    int force_clamping;         // HD_MAX_FORCE_CLAMPING enabled
    int software_force_limit;   // HD_SOFTWARE_FORCE_LIMIT enabled
    int scheduler_running;
    int callbacks_scheduled;
    int init_calls;
    int disable_calls;
    int calibration_updates;
    unsigned last_update_style;
    unsigned long long frames;
    unsigned long long force_writes;    // frames in which HD_CURRENT_FORCE was set
    double last_force[3];               // force applied at the last frame end (N)
    unsigned long long force_change_frame;  // `frames` count at the frame that last changed it
    double max_force_norm;              // largest |force| applied since reset
    int non_finite_force;               // a non-finite force was set
    unsigned long long torque_writes;   // frames in which HD_CURRENT_TORQUE was set
    double last_torque[3];              // as set (mN·m)
    unsigned long long writes_outside_frame;
    char last_init_name[64];            // "" for the default device
};

using fake_hd_reset_fn = void (*)();
using fake_hd_state_fn = void (*)(FakeHdState*);
using fake_hd_set_init_error_fn = void (*)(unsigned code);
using fake_hd_set_calibration_fn = void (*)(unsigned status, int supported_styles, int update_fixes);
using fake_hd_set_start_error_fn = void (*)(unsigned code);
using fake_hd_inject_error_fn = void (*)(unsigned code);  // pushed at the end of the next frame
using fake_hd_set_model_fn = void (*)(const char* model);
// Device figures; 0 (or an empty box) means "not reported" (the query fails with HD_INVALID_ENUM).
using fake_hd_set_figures_fn = void (*)(double max_force_N, double continuous_N, double stiffness_N_per_mm,
                                        const double workspace_mm[6], int input_dof, int output_dof);
using fake_hd_set_transform_fn = void (*)(const double column_major_mm[16]);
using fake_hd_set_velocity_fn = void (*)(const double mm_per_s[3]);
using fake_hd_set_buttons_fn = void (*)(int buttons);

}  // extern "C"
