//! Typed views of a whole-file [`Log`]: one topic, checked once, its rows decoded per instance
//! or for all instances in file order.

use std::fmt;

use super::{Topic, TypedDecoder, TypedError};
use crate::read::Log;

/// One topic of a [`Log`] read as `T` ([`Log::topic`]): checked against the file's format once.
pub struct TypedTopic<'a, T> {
    log: &'a Log<'a>,
    /// The topic name read (`T`'s own, or another given to [`Log::topic_as`]).
    topic: String,
    decoder: TypedDecoder<T>,
    /// Indices of the topic's subscriptions, in file order.
    subs: Vec<usize>,
}

impl<T> fmt::Debug for TypedTopic<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("TypedTopic")
            .field("decoder", &self.decoder)
            .field("subscriptions", &self.subs)
            .finish_non_exhaustive()
    }
}

impl Log<'_> {
    /// The rows of topic `T` (the format named `T::FORMAT.name`), after checking `T` against
    /// the file's definition of it. Errors: the file lacks the format, never subscribes it, or
    /// the struct does not match (every difference listed).
    ///
    /// ```
    /// use ulog_runtime::{Log, ULog, Writer, WriterOptions};
    ///
    /// #[derive(ULog, Debug, PartialEq)]
    /// struct Battery { timestamp: u64, voltage_v: f32 }
    ///
    /// let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
    /// let battery = w.topic::<Battery>(0)?;
    /// w.write(&battery, &Battery { timestamp: 10, voltage_v: 15.2 })?;
    /// let bytes = w.into_inner();
    ///
    /// let log = Log::from_slice(&bytes)?;
    /// let rows: Vec<Battery> = log.topic::<Battery>()?.instance(0)?.collect();
    /// assert_eq!(rows, [Battery { timestamp: 10, voltage_v: 15.2 }]);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn topic<T: Topic>(&self) -> Result<TypedTopic<'_, T>, TypedError> {
        self.topic_as(T::FORMAT.name)
    }

    /// The rows of the topic named `topic` read as `T`: one type for the topics PX4 logs
    /// with one layout under several names (`# TOPICS` in its `.msg` files, e.g.
    /// `vehicle_attitude` and `estimator_attitude`), checked against that topic's format as
    /// [`Log::topic`] checks `T`'s own. [`TypedFormat::topics`](super::TypedFormat::topics)
    /// lists the names a type declares; any other name whose format matches works too.
    ///
    /// ```
    /// use ulog_runtime::{Log, ULog, Writer, WriterOptions};
    ///
    /// #[derive(ULog, Debug, PartialEq)]
    /// #[ulog(topics("vehicle_attitude", "estimator_attitude"))]
    /// struct VehicleAttitude { timestamp: u64, q: [f32; 4] }
    ///
    /// let mut w = Writer::new(Vec::new(), WriterOptions::default())?;
    /// let est = w.topic_as::<VehicleAttitude>("estimator_attitude", 0)?;
    /// w.write(&est, &VehicleAttitude { timestamp: 5, q: [1.0, 0.0, 0.0, 0.0] })?;
    /// let log = Log::from_vec(w.into_inner())?;
    ///
    /// assert_eq!(VehicleAttitude::FORMAT.topics, ["vehicle_attitude", "estimator_attitude"]);
    /// let rows: Vec<_> = log.topic_as::<VehicleAttitude>("estimator_attitude")?.instance(0)?.collect();
    /// assert_eq!(rows[0].timestamp, 5);
    /// assert!(log.topic::<VehicleAttitude>().is_err()); // not logged under its own name
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn topic_as<T: Topic>(&self, topic: &str) -> Result<TypedTopic<'_, T>, TypedError> {
        let decoder = TypedDecoder::<T>::new_as(self.metadata().schema(), topic)?;
        let subs: Vec<usize> = self
            .subscriptions()
            .iter()
            .filter(|s| s.format() == Some(decoder.format()))
            .map(|s| s.index())
            .collect();
        debug_assert!(subs.iter().all(|&i| {
            let sizes = self.subscriptions()[i].payload_sizes();
            sizes.is_some_and(|(min, _)| min >= decoder.min_len())
        }));
        if subs.is_empty() {
            return Err(TypedError::NotLogged {
                topic: topic.to_owned(),
            });
        }
        Ok(TypedTopic {
            log: self,
            topic: topic.to_owned(),
            decoder,
            subs,
        })
    }
}

impl<'a, T: Topic> TypedTopic<'a, T> {
    /// The instances (`multi_id`s) logged, ascending.
    pub fn multi_ids(&self) -> Vec<u8> {
        let mut ids: Vec<u8> = self
            .subs
            .iter()
            .map(|&i| self.log.subscriptions()[i].multi_id)
            .collect();
        ids.sort_unstable();
        ids.dedup();
        ids
    }

    /// The rows of one instance, in file order.
    pub fn instance(&self, multi_id: u8) -> Result<TypedRows<'a, T>, TypedError> {
        let subs: Vec<usize> = self
            .subs
            .iter()
            .copied()
            .filter(|&i| self.log.subscriptions()[i].multi_id == multi_id)
            .collect();
        if subs.is_empty() {
            return Err(TypedError::NoInstance {
                topic: self.topic.clone(),
                multi_id,
                available: self.multi_ids(),
            });
        }
        Ok(TypedRows {
            merge: self.merge(&subs),
            decoder: self.decoder.clone(),
        })
    }

    /// The rows of every instance, in file order, each with its `multi_id`.
    pub fn rows(&self) -> TopicRows<'a, T> {
        TopicRows {
            merge: self.merge(&self.subs),
            decoder: self.decoder.clone(),
        }
    }

    /// The topic name read.
    pub fn name(&self) -> &str {
        &self.topic
    }

    /// The checked decoder.
    pub fn decoder(&self) -> &TypedDecoder<T> {
        &self.decoder
    }

    fn merge(&self, subs: &[usize]) -> Merge<'a> {
        Merge {
            log: self.log,
            heads: subs
                .iter()
                .map(|&i| {
                    let multi_id = self.log.subscriptions()[i].multi_id;
                    (multi_id, self.log.row_offsets(i).iter())
                })
                .collect(),
        }
    }
}

/// The rows of several subscriptions merged into file order (by their offsets).
#[derive(Clone)]
struct Merge<'a> {
    log: &'a Log<'a>,
    /// Each subscription's remaining row offsets, with its `multi_id`.
    heads: Vec<(u8, std::slice::Iter<'a, u64>)>,
}

impl<'a> Merge<'a> {
    /// The next row's `multi_id` and data.
    #[inline]
    fn next(&mut self) -> Option<(u8, &'a [u8])> {
        let (multi_id, n) = match self.heads.as_mut_slice() {
            [(m, one)] => (*m, *one.next()?),
            heads => {
                let (_, (m, head)) = heads
                    .iter_mut()
                    .filter_map(|h| h.1.as_slice().first().copied().map(|n| (n, h)))
                    .min_by_key(|(n, _)| *n)?;
                (*m, *head.next()?)
            }
        };
        Some((multi_id, self.log.row_data(n)))
    }

    fn len(&self) -> usize {
        self.heads.iter().map(|h| h.1.len()).sum()
    }
}

/// Decoded rows of one topic instance ([`TypedTopic::instance`]).
pub struct TypedRows<'a, T> {
    merge: Merge<'a>,
    decoder: TypedDecoder<T>,
}

impl<T: Topic> Iterator for TypedRows<'_, T> {
    type Item = T;

    #[inline]
    fn next(&mut self) -> Option<T> {
        let (_, data) = self.merge.next()?;
        Some(self.decoder.decode_accepted(data))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.merge.len(), Some(self.merge.len()))
    }
}

/// Decoded rows of every instance of a topic, with their `multi_id`s ([`TypedTopic::rows`]).
pub struct TopicRows<'a, T> {
    merge: Merge<'a>,
    decoder: TypedDecoder<T>,
}

impl<T: Topic> Iterator for TopicRows<'_, T> {
    type Item = (u8, T);

    #[inline]
    fn next(&mut self) -> Option<(u8, T)> {
        let (multi_id, data) = self.merge.next()?;
        Some((multi_id, self.decoder.decode_accepted(data)))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.merge.len(), Some(self.merge.len()))
    }
}

impl<T: Topic> ExactSizeIterator for TypedRows<'_, T> {}

impl<T: Topic> ExactSizeIterator for TopicRows<'_, T> {}

impl<T> fmt::Debug for TypedRows<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("TypedRows")
            .field("remaining", &self.merge.len())
            .finish()
    }
}

impl<T> fmt::Debug for TopicRows<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("TopicRows")
            .field("remaining", &self.merge.len())
            .finish()
    }
}
