//! Bus load of a channel, checked when a configuration is loaded (CiA 301 needs no more: the
//! cyclic traffic is fixed by the PDO mappings the controller configures). Classical base-format frame with n data bytes: 47 + 8n bits without
//! stuffing, plus at most ⌊(34 + 8n − 1)/4⌋ stuff bits (the 34 + 8n stuffed bits from SOF to CRC,
//! one stuff bit after every 4 in the worst case): 8 bytes 111–135 bits, SYNC (0 bytes) 47–55.

/// Share of the bus above which a configuration is refused (worst case, with stuffing).
pub const MAX_BUS_LOAD: f64 = 0.70;

/// Bits of a classical base-format frame with `n` data bytes: (without stuffing, worst case).
pub fn frame_bits(n: u32) -> (u32, u32) {
    let nominal = 47 + 8 * n;
    let stuff = (34 + 8 * n - 1) / 4;
    (nominal, nominal + stuff)
}

/// Cyclic traffic of one channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelTraffic {
    /// Axes (drives) on the channel.
    pub axes: u32,
    /// PDOs per cycle by their number of data bytes (index 0–8): an RPDO and a TPDO per axis,
    /// of the lengths their mappings give.
    pub pdo_frames: [u32; 9],
    /// SYNC / PDO cycle rate, Hz.
    pub cycle_hz: f64,
    /// Bit rate, bit/s.
    pub bitrate: f64,
    /// Heartbeat period of each drive, s (0 = none).
    pub heartbeat_period: f64,
}

/// The computed load of one channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BusLoad {
    /// Share without stuff bits.
    pub nominal: f64,
    /// Share with the worst-case stuff bits.
    pub worst: f64,
    /// Bits per second, worst case.
    pub worst_bits_per_s: f64,
}

impl ChannelTraffic {
    /// The traffic of `axes` axes with the project's default 8-byte RPDO and TPDO.
    pub fn eight_byte_pdos(axes: u32, cycle_hz: f64, bitrate: f64, heartbeat_period: f64) -> Self {
        let mut pdo_frames = [0; 9];
        pdo_frames[8] = 2 * axes;
        ChannelTraffic {
            axes,
            pdo_frames,
            cycle_hz,
            bitrate,
            heartbeat_period,
        }
    }

    /// Load of the channel: SYNC + the PDOs per cycle + heartbeats.
    pub fn load(&self) -> BusLoad {
        let (sync, sync_w) = frame_bits(0);
        let (hb, hb_w) = frame_bits(1);
        let (mut pdo, mut pdo_w) = (0.0, 0.0);
        for (n, count) in self.pdo_frames.iter().enumerate() {
            let (b, w) = frame_bits(n as u32);
            pdo += (*count * b) as f64;
            pdo_w += (*count * w) as f64;
        }
        let hb_rate = if self.heartbeat_period > 0.0 {
            self.axes as f64 / self.heartbeat_period
        } else {
            0.0
        };
        let per_s = |s: u32, p: f64, h: u32| self.cycle_hz * (s as f64 + p) + hb_rate * h as f64;
        let nominal = per_s(sync, pdo, hb);
        let worst = per_s(sync_w, pdo_w, hb_w);
        BusLoad {
            nominal: nominal / self.bitrate,
            worst: worst / self.bitrate,
            worst_bits_per_s: worst,
        }
    }
}

/// A channel over the budget.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "channel {channel}: {axes} axes at {cycle_hz} Hz on {bitrate} bit/s load the bus {:.1}–{:.1} % \
     (without/with worst-case bit stuffing), above the {:.0} % allowed; use fewer axes per channel, \
     a lower cycle rate or a faster bus",
    nominal * 100.0, worst * 100.0, limit * 100.0
)]
pub struct OverBudget {
    /// Name of the channel (interface).
    pub channel: String,
    /// Axes on it.
    pub axes: u32,
    /// Cycle rate, Hz.
    pub cycle_hz: f64,
    /// Bit rate, bit/s.
    pub bitrate: f64,
    /// Nominal share.
    pub nominal: f64,
    /// Worst-case share.
    pub worst: f64,
    /// Allowed share.
    pub limit: f64,
}

/// Checks one channel against [`MAX_BUS_LOAD`]; returns its load or the refusal with the numbers.
pub fn check_channel(channel: &str, traffic: &ChannelTraffic) -> Result<BusLoad, OverBudget> {
    let l = traffic.load();
    if l.worst > MAX_BUS_LOAD || !l.worst.is_finite() {
        Err(OverBudget {
            channel: channel.to_string(),
            axes: traffic.axes,
            cycle_hz: traffic.cycle_hz,
            bitrate: traffic.bitrate,
            nominal: l.nominal,
            worst: l.worst,
            limit: MAX_BUS_LOAD,
        })
    } else {
        Ok(l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn traffic(axes: u32) -> ChannelTraffic {
        ChannelTraffic::eight_byte_pdos(axes, 1000.0, 1e6, 0.1)
    }

    #[test]
    fn shorter_pdos_load_the_bus_less() {
        // 3 axes with 6-byte RPDOs and TPDOs (95–115 bits each) at 1 kHz, heartbeats 30/s:
        // 61.9–74.7 %, still refused; 2 axes with 4-byte PDOs pass
        let mut t = traffic(3);
        t.pdo_frames = [0, 0, 0, 0, 0, 0, 6, 0, 0];
        let l = t.load();
        assert!((l.nominal - 0.618_65).abs() < 1e-9, "{l:?}");
        assert!((l.worst - 0.746_95).abs() < 1e-9, "{l:?}");
        assert!(check_channel("can0", &t).is_err());
        let mut t = traffic(2);
        t.pdo_frames = [0, 0, 0, 0, 4, 0, 0, 0, 0];
        assert!(check_channel("can0", &t).unwrap().worst < traffic(2).load().worst);
    }

    #[test]
    fn frame_sizes_match_the_standard_numbers() {
        assert_eq!(frame_bits(8), (111, 135));
        assert_eq!(frame_bits(0), (47, 55));
    }

    #[test]
    fn two_axes_pass_three_and_four_are_refused_with_their_numbers() {
        let l2 = check_channel("can0", &traffic(2)).unwrap();
        assert!((0.49..0.50).contains(&l2.nominal), "{l2:?}");
        assert!((0.59..0.60).contains(&l2.worst), "{l2:?}");
        let e3 = check_channel("can1", &traffic(3)).unwrap_err();
        assert!(
            (0.71..0.72).contains(&e3.nominal) && (0.86..0.87).contains(&e3.worst),
            "{e3:?}"
        );
        let msg = e3.to_string();
        assert!(
            msg.contains("can1") && msg.contains("71.") && msg.contains("86."),
            "{msg}"
        );
        let e4 = check_channel("can2", &traffic(4)).unwrap_err();
        assert!(
            (0.93..0.95).contains(&e4.nominal) && (1.13..1.15).contains(&e4.worst),
            "{e4:?}"
        );
    }
}
