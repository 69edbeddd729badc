//! Building an axis: every check of its configuration (the error names the field), the tuning of
//! its loops and its initial, disabled state. Runs once, never in the loop.

use super::*;

impl Axis {
    /// Validates `config`, tunes the loops and builds a disabled axis in current mode.
    pub fn new(config: &AxisConfig) -> Result<Self> {
        let c = config;
        c.model.validate()?;
        positive("continuous current (A)", c.continuous_current)?;
        positive("peak current (A)", c.peak_current)?;
        positive("over-current trip (A)", c.overcurrent_trip)?;
        positive("max speed (rad/s)", c.max_speed)?;
        positive("following error limit (rad)", c.following_error_limit)?;
        positive("quick-stop deceleration (rad/s²)", c.quick_stop_deceleration)?;
        if c.peak_current < c.continuous_current {
            return Err(invalid(
                "peak current (A)",
                c.peak_current,
                "must be >= the continuous current",
            ));
        }
        if c.overcurrent_trip <= c.peak_current {
            return Err(invalid(
                "over-current trip (A)",
                c.overcurrent_trip,
                "must be > the peak current",
            ));
        }
        let m = &c.model;
        let n = m.gearbox.ratio;
        let emf_at_max = m.motor.back_emf_constant * c.max_speed * n;
        if emf_at_max + m.motor.resistance * c.continuous_current > m.max_voltage() {
            return Err(invalid(
                "max speed (rad/s)",
                c.max_speed,
                &format!(
                    "back-EMF {emf_at_max:.2} V plus R·I_cont exceeds the usable bus voltage {:.2} V",
                    m.max_voltage()
                ),
            ));
        }
        if c.emf_filter_hz.is_nan() || c.emf_filter_hz <= 0.0 {
            return Err(invalid(
                "EMF filter (Hz)",
                c.emf_filter_hz,
                "must be > 0 (infinite: no filter)",
            ));
        }
        if let Some(f) = c.speed_reference_filter_hz {
            if f.is_nan() || f <= 0.0 {
                return Err(invalid(
                    "speed reference filter (Hz)",
                    f,
                    "must be > 0 (infinite: no filter)",
                ));
            }
        }
        let [tc, ts, tp] = c.rates.periods();
        let tuning = tune_cascade(m, [tc, ts, tp], &c.tuning)?;
        finite("tuned speed gain", tuning.speed.kp)?;
        positive("max quantisation ripple share", c.max_quantisation_ripple_share)?;
        let ripple = tuning.quantisation_ripple_rms;
        if ripple > c.max_quantisation_ripple_share * c.continuous_current {
            return Err(invalid(
                "observer bandwidth (Hz)",
                c.tuning.observer_bandwidth_hz,
                &format!(
                    "encoder quantisation puts {ripple:.3} A RMS on the current reference (Kp·Δω), above {:.0} % of the \
                     continuous current {:.2} A: lower the observer bandwidth or use a finer encoder",
                    100.0 * c.max_quantisation_ripple_share,
                    c.continuous_current
                ),
            ));
        }
        let observer = TrackingObserver::new(
            c.tuning.observer_bandwidth_hz,
            tc,
            if c.tuning.observer_acceleration_input {
                m.acceleration_per_amp()
            } else {
                0.0
            },
        )?;

        let rad_per_count = m.radians_per_count();
        let current_loop = CurrentLoop::new(
            Pi::new(tuning.current.kp, tuning.current.ki, tc, c.anti_windup),
            m.bus_voltage,
            m.max_voltage(),
            if c.emf_feedforward {
                m.motor.back_emf_constant * n
            } else {
                0.0
            },
            c.peak_current,
        );
        let thermal = ThermalState::new(&c.thermal, m.motor.resistance)?;
        let ref_filter_hz = c.speed_reference_filter_hz.unwrap_or(tuning.speed_reference_filter_hz);
        let speed_loop = SpeedLoop::new(
            Pi::new(tuning.speed.kp, tuning.speed.ki, ts, c.anti_windup),
            c.max_speed,
            LowPass::new(ref_filter_hz, ts),
            LowPass::new(c.tuning.speed_output_filter_hz, ts),
        );
        let position_loop = PositionLoop::new(
            tuning.position.kp,
            1.0 / m.acceleration_per_amp(),
            c.velocity_feedforward,
            c.acceleration_feedforward,
        );
        if let Some(p) = c.setpoint_period {
            positive("setpoint period (s)", p)?;
            if p < ts * (1.0 - 1e-9) {
                return Err(invalid(
                    "setpoint period (s)",
                    p,
                    "must be at least one speed-loop period",
                ));
            }
        }
        if c.setpoint_max_missed == 0 {
            return Err(invalid("setpoint max missed", 0.0, "must be >= 1"));
        }
        non_negative("following error per speed (s)", c.following_error_per_speed)?;
        above(
            "overspeed limit (rad/s)",
            c.overspeed_limit,
            c.max_speed,
            "the max speed",
        )?;
        if let Some((lo, hi)) = c.position_limits {
            finite("position limit lower (rad)", lo)?;
            finite("position limit upper (rad)", hi)?;
            if lo >= hi {
                return Err(invalid("position limit lower (rad)", lo, "must be < the upper limit"));
            }
        }
        positive("bus under-voltage (V)", c.bus_undervoltage)?;
        above(
            "bus over-voltage (V)",
            c.bus_overvoltage,
            m.bus_voltage,
            "the nominal bus voltage",
        )?;
        if c.bus_undervoltage >= m.bus_voltage {
            return Err(invalid(
                "bus under-voltage (V)",
                c.bus_undervoltage,
                "must be < the nominal bus voltage",
            ));
        }
        let stop_timeout = 2.0 * c.max_speed / c.quick_stop_deceleration + 0.2;
        if let Some(b) = c.holding_brake {
            for (what, v) in [
                ("brake release delay (s)", b.release_delay),
                ("brake engage delay (s)", b.engage_delay),
            ] {
                non_negative(what, v)?;
                if v > stop_timeout {
                    return Err(invalid(
                        what,
                        v,
                        &format!("must not exceed the stop time {stop_timeout:.3} s (the axis could not hold until the brake acts)"),
                    ));
                }
            }
        }
        // An encoder may move at most twice the largest speed's worth of counts per current period.
        let jump_limit = (2.0 * c.max_speed * tc / rad_per_count).ceil() as u64 + 2;
        Ok(Axis {
            config: *c,
            tuning,
            rad_per_count,
            speed_period: ts,
            current_period: tc,
            jump_limit,
            // "Stopped": 1 % of the largest speed, or three encoder counts per speed period.
            standstill: (0.01 * c.max_speed).max(3.0 * rad_per_count / ts),
            stop_timeout,
            bus_nominal: m.bus_voltage,
            brake_engaged: c.holding_brake.is_some(),
            brake_timer: 0.0,
            disable_pending: false,
            q_hold: 0.0,
            current_loop,
            thermal,
            emf_speed: LowPass::new(c.emf_filter_hz, ts),
            speed_loop,
            position_loop,
            interpolator: SetpointInterpolator::new(c.setpoint_period.unwrap_or(tp), c.setpoint_max_missed),
            interpolating: c.setpoint_period.is_some(),
            amps_per_joint_torque: 1.0 / (m.motor.torque_constant * n),
            primed: false,
            count_offset: 0,
            last_counts: 0,
            encoder_position: 0.0,
            observer,
            position: 0.0,
            speed: 0.0,
            state: AxisState::Disabled,
            mode: Mode::Current,
            current_command: 0.0,
            speed_command: 0.0,
            q_ref: 0.0,
            qd_ref: 0.0,
            qdd_ref: 0.0,
            torque_feedforward: 0.0,
            torque_segment: [0.0; 2],
            host_torque: false,
            position_output: PositionOutput::default(),
            current_reference: 0.0,
            duty: 0.0,
            stop_reference: 0.0,
            stop_time: 0.0,
        })
    }
}

/// Checks that `value` is above `bound` (NaN is not), which the error calls `bound_name`.
fn above(what: &str, value: f64, bound: f64, bound_name: &str) -> Result<()> {
    if value.is_nan() || value <= bound {
        return Err(invalid(what, value, &format!("must be > {bound_name}")));
    }
    Ok(())
}

fn invalid(what: &str, value: f64, reason: &str) -> Error {
    Error::InvalidParameter {
        what: what.into(),
        value,
        reason: reason.into(),
    }
}
