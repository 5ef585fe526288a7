//! Battery brownout: while armed, the voltage of a battery instance (`voltage_v`, else
//! `voltage_filtered_v`) per cell below 3.3 V for at least 1 s, every reading of the
//! episode below: critical. The cell count is the parameter `BAT<n>_N_CELLS` (older PX4:
//! `BAT_N_CELLS`) when the log has it, else the topic's `cell_count`, else estimated from
//! the highest voltage seen so far (a LiPo cell holds at most 4.35 V).

use super::{Diagnostic, Episode, Evidence, Severity, secs};
use crate::analysis::LazyIndex;
use crate::analysis::state::FlightState;
use crate::columns::Leaf;
use crate::read::Metadata;

/// Volts per cell below which a pack browns out.
pub const CELL_CRITICAL_V: f64 = 3.3;
/// How long the voltage must stay below, µs.
pub const MIN_DURATION_US: u64 = 1_000_000;

/// Where `battery_status`'s fields are.
pub(crate) struct Fields {
    multi_id: u8,
    voltage: Leaf,
    current: Option<Leaf>,
    cell_count: Option<Leaf>,
}

impl Fields {
    pub(crate) fn bind(multi_id: u8, index: &LazyIndex<'_>) -> Option<Fields> {
        Some(Fields {
            multi_id,
            voltage: index
                .get("voltage_v")
                .or_else(|| index.get("voltage_filtered_v"))?,
            current: index
                .get("current_a")
                .or_else(|| index.get("current_filtered_a")),
            cell_count: index.get("cell_count"),
        })
    }
}

/// The lowest voltage of an episode, its cells, their source, the current then.
type Worst = (f64, u32, &'static str, Option<f64>);

#[derive(Debug, Clone, Default)]
struct Battery {
    max_voltage: f64,
    cell_count: Option<u32>,
    episode: Episode,
    /// The open episode's worst.
    worst: Option<Worst>,
}

/// Every battery instance's state, and the episodes found.
#[derive(Debug, Clone, Default)]
pub(crate) struct Brownout {
    batteries: Vec<(u8, Battery)>,
    found: Vec<(u8, u64, u64, Worst)>,
    /// Cells from the parameters, per instance (0 to 7), once looked up.
    meta_cells: Option<Vec<Option<u32>>>,
}

/// Cells of battery `multi_id` from the parameters.
pub(crate) fn cells_parameter(meta: &Metadata, multi_id: u8) -> Option<u32> {
    let param = |name: &str| {
        meta.parameter(name)
            .map(crate::read::ParamValue::as_f64)
            .filter(|n| *n > 0.0 && *n < 64.0)
    };
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    param(&format!("BAT{}_N_CELLS", u32::from(multi_id) + 1))
        .or_else(|| (multi_id == 0).then(|| param("BAT_N_CELLS")).flatten())
        .map(|n| n as u32)
}

impl Brownout {
    /// Learns the parameters' cell counts (before the rows).
    pub(crate) fn start(&mut self, meta: &Metadata) {
        self.meta_cells = Some(
            (0..=u8::MAX)
                .map(|m| cells_parameter(meta, m))
                .take(8)
                .collect(),
        );
    }

    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    pub(crate) fn row(&mut self, f: &Fields, data: &[u8], t: u64, state: &FlightState) {
        let param_cells = self
            .meta_cells
            .as_ref()
            .and_then(|c| c.get(usize::from(f.multi_id)).copied().flatten());
        let b = match self.batteries.iter().position(|(m, _)| *m == f.multi_id) {
            Some(i) => &mut self.batteries[i].1,
            None => {
                self.batteries.push((f.multi_id, Battery::default()));
                &mut self.batteries.last_mut().expect("pushed").1
            }
        };
        let Some(v) = f.voltage.f64(data).filter(|v| v.is_finite() && *v > 0.0) else {
            return;
        };
        b.max_voltage = b.max_voltage.max(v);
        if let Some(n) = f
            .cell_count
            .and_then(|l| l.f64(data))
            .filter(|n| *n > 0.0 && *n < 64.0)
        {
            b.cell_count = Some(n as u32);
        }
        let (cells, from) = match (param_cells, b.cell_count) {
            (Some(n), _) => (n, "parameter"),
            (None, Some(n)) => (n, "cell_count"),
            (None, None) => (((b.max_voltage / 4.35).ceil() as u32).max(1), "estimated"),
        };
        let low = state.armed && v / f64::from(cells) < CELL_CRITICAL_V;
        if low {
            let current = f
                .current
                .and_then(|l| l.f64(data))
                .filter(|c| c.is_finite() && *c >= 0.0);
            if b.worst.is_none_or(|w| v < w.0) {
                b.worst = Some((v, cells, from, current));
            }
        }
        if let Some((start, end)) = b.episode.see(low, t)
            && let Some(w) = b.worst.take()
            && end - start >= MIN_DURATION_US
        {
            self.found.push((f.multi_id, start, end, w));
        }
    }

    /// Whether any row was taken.
    pub(crate) fn seen(&self) -> bool {
        !self.batteries.is_empty()
    }

    pub(crate) fn finish(mut self, end: u64) -> Vec<Diagnostic> {
        for (m, b) in &mut self.batteries {
            if let Some((start, stop)) = b.episode.close(end)
                && let Some(w) = b.worst.take()
                && stop - start >= MIN_DURATION_US
            {
                self.found.push((*m, start, stop, w));
            }
        }
        self.found
            .into_iter()
            .map(|(multi_id, start, end, (v, cells, from, current))| {
                let threshold = f64::from(cells) * CELL_CRITICAL_V;
                Diagnostic {
                    id: "battery_brownout".to_owned(),
                    summary: format!(
                        "Battery {multi_id} at {v:.2} V ({:.2} V per cell of {cells}S, below \
                         {CELL_CRITICAL_V} V) for {:.1} s from {:.1} s while armed",
                        v / f64::from(cells),
                        secs(end - start),
                        secs(start)
                    ),
                    severity: Severity::Critical,
                    timestamp_us: start,
                    end_timestamp_us: Some(end),
                    evidence: Evidence::BatteryBrownout {
                        multi_id,
                        voltage_v: v,
                        cell_voltage_v: v / f64::from(cells),
                        cells,
                        cells_from: from.to_owned(),
                        critical_threshold_v: threshold,
                        current_a: current,
                    },
                }
            })
            .collect()
    }
}
