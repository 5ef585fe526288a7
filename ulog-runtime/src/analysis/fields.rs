//! Per-field statistics: minimum, maximum and mean of every numeric field of every topic
//! instance (`bool` and `char` left out, `timestamp` too), over its finite values, each
//! row's leaves taken as typed runs.

use super::FieldStat;
use crate::read::Subscription;
use crate::schema::{Primitive, Schema};
use crate::value::{RowPlan, VisitLeaves};

/// One topic instance's fields.
#[derive(Debug, Clone)]
struct Acc {
    topic: String,
    multi_id: u8,
    plan: RowPlan,
    /// Per leaf: name, and whether it is counted.
    names: Vec<(String, bool)>,
    min: Vec<f64>,
    max: Vec<f64>,
    sum: Vec<f64>,
    count: Vec<u64>,
}

/// Every topic instance's field statistics.
#[derive(Debug, Clone, Default)]
pub(super) struct FieldStats {
    accs: Vec<Acc>,
}

impl FieldStats {
    /// The accumulator of a subscription's rows (one per topic instance and format).
    pub(super) fn bind(&mut self, sub: &Subscription, schema: &Schema) -> Option<usize> {
        let plan = sub.plan(schema)?;
        if let Some(k) = self
            .accs
            .iter()
            .position(|a| a.topic == sub.name && a.multi_id == sub.multi_id && a.plan == *plan)
        {
            return Some(k);
        }
        let names: Vec<(String, bool)> = plan
            .columns(schema)
            .into_iter()
            .map(|c| {
                let counted = c.name != "timestamp"
                    && !matches!(c.primitive, Primitive::Bool | Primitive::Char);
                (c.name, counted)
            })
            .collect();
        let n = names.len();
        self.accs.push(Acc {
            topic: sub.name.clone(),
            multi_id: sub.multi_id,
            plan: plan.clone(),
            names,
            min: vec![f64::INFINITY; n],
            max: vec![f64::NEG_INFINITY; n],
            sum: vec![0.0; n],
            count: vec![0; n],
        });
        Some(self.accs.len() - 1)
    }

    #[inline]
    pub(super) fn row(&mut self, k: usize, data: &[u8]) {
        let acc = &mut self.accs[k];
        let Acc {
            plan,
            names,
            min,
            max,
            sum,
            count,
            ..
        } = acc;
        plan.visit_runs(
            data,
            &mut Visit {
                names,
                min,
                max,
                sum,
                count,
                at: 0,
            },
        );
    }

    /// The statistics of every counted field with a finite value, by topic, instance and
    /// field order.
    pub(super) fn finish(&self) -> Vec<FieldStat> {
        let mut out = Vec::new();
        let mut accs: Vec<&Acc> = self.accs.iter().collect();
        accs.sort_by(|a, b| (&a.topic, a.multi_id).cmp(&(&b.topic, b.multi_id)));
        for a in accs {
            for (i, (name, counted)) in a.names.iter().enumerate() {
                if !counted || a.count[i] == 0 {
                    continue;
                }
                // Several formats of one instance (a resubscription): merged by name.
                if let Some(f) = out.iter_mut().find(|f: &&mut FieldStat| {
                    f.topic == a.topic && f.multi_id == a.multi_id && f.field == *name
                }) {
                    let total = f.count + a.count[i];
                    f.mean = (f.mean * f.count as f64 + a.sum[i]) / total as f64;
                    f.min = f.min.min(a.min[i]);
                    f.max = f.max.max(a.max[i]);
                    f.count = total;
                    continue;
                }
                out.push(FieldStat {
                    topic: a.topic.clone(),
                    multi_id: a.multi_id,
                    field: name.clone(),
                    min: a.min[i],
                    max: a.max[i],
                    mean: a.sum[i] / a.count[i] as f64,
                    count: a.count[i],
                });
            }
        }
        out
    }
}

struct Visit<'a> {
    names: &'a [(String, bool)],
    min: &'a mut [f64],
    max: &'a mut [f64],
    sum: &'a mut [f64],
    count: &'a mut [u64],
    at: usize,
}

impl Visit<'_> {
    #[inline]
    fn take(&mut self, values: impl Iterator<Item = f64>) {
        for v in values {
            let i = self.at;
            self.at += 1;
            if self.names[i].1 && v.is_finite() {
                self.min[i] = self.min[i].min(v);
                self.max[i] = self.max[i].max(v);
                self.sum[i] += v;
                self.count[i] += 1;
            }
        }
    }
}

macro_rules! visit {
    ($($name:ident: $arr:ty => $conv:expr),* $(,)?) => {
        impl<'r> VisitLeaves<'r> for Visit<'_> {
            $(
                #[inline]
                #[allow(clippy::cast_precision_loss)]
                fn $name(&mut self, v: &'r [$arr]) {
                    self.take(v.iter().map($conv));
                }
            )*
            fn bool(&mut self, v: &'r [u8]) {
                self.at += v.len();
            }
            fn char(&mut self, v: &'r [u8]) {
                self.at += v.len();
            }
        }
    };
}

visit! {
    int8: u8 => |b: &u8| f64::from(*b as i8),
    uint8: u8 => |b: &u8| f64::from(*b),
    int16: [u8; 2] => |b: &[u8; 2]| f64::from(i16::from_le_bytes(*b)),
    uint16: [u8; 2] => |b: &[u8; 2]| f64::from(u16::from_le_bytes(*b)),
    int32: [u8; 4] => |b: &[u8; 4]| f64::from(i32::from_le_bytes(*b)),
    uint32: [u8; 4] => |b: &[u8; 4]| f64::from(u32::from_le_bytes(*b)),
    int64: [u8; 8] => |b: &[u8; 8]| i64::from_le_bytes(*b) as f64,
    uint64: [u8; 8] => |b: &[u8; 8]| u64::from_le_bytes(*b) as f64,
    float: [u8; 4] => |b: &[u8; 4]| f64::from(f32::from_le_bytes(*b)),
    double: [u8; 8] => |b: &[u8; 8]| f64::from_le_bytes(*b),
}
