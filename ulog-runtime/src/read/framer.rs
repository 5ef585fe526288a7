//! Finds message boundaries in a window of file bytes and recovers when they are lost.
//!
//! The framer is shared by the whole-file and the streaming reader: it sees a window
//! `[base, base + window.len())` of the file and asks for more bytes when it needs them, so its
//! memory use is bounded by two messages whatever the file size.
//!
//! A message is accepted when its content is *strongly* plausible on its own (a `D` whose
//! `msg_id` is subscribed and whose size fits that format, an `S` carrying the sync magic, a
//! key that looks like `type name`...), or when it is *weakly* plausible (known type, big
//! enough) and the next header is weakly plausible too. Anything else means the boundary is
//! lost: the framer scans forward, one byte at a time, from just after the last accepted
//! message start, for a strongly plausible message followed by a plausible header (or for the
//! sync magic), and reports the bytes it skipped. Starting the scan just after the last
//! accepted message recovers the message that follows a damaged size field.

use super::message::{HEADER_LEN, MESSAGE_HEADER_LEN, MessageType, SYNC_MAGIC, u16_at};

/// Bytes ahead of the message read that the fast path asks the processor to fetch, in a
/// window of more than [`PREFETCH_MIN_WINDOW`] bytes (a file in memory, not a stream's buffer).
const PREFETCH_AHEAD: usize = 2048;
const PREFETCH_MIN_WINDOW: usize = 4 << 20;

/// What the framer found next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Frame {
    /// A message: header at `offset`, `size` payload bytes after the 3-byte header.
    Message { offset: u64, ty: u8, size: u16 },
    /// Bytes `[from, to)` were not part of any accepted message.
    Skipped { from: u64, to: u64 },
    /// The message at `prev` declared a size that runs into the message found at `next`.
    Overlap { prev: u64, next: u64 },
    /// A message at `offset` runs past the end of its segment or the file.
    Truncated {
        offset: u64,
        declared: Option<u16>,
        available: u64,
    },
    /// An appended-data offset of the flag bits that cannot be right.
    BadAppendedOffset { offset: u64 },
    /// More bytes are needed; bytes before `keep_from` will not be needed again.
    NeedMore { keep_from: u64 },
    /// No more messages.
    End,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Plausibility {
    Invalid,
    Unknown,
    Weak,
    Strong,
}

#[derive(Debug, Clone, Copy)]
struct Resync {
    bad: u64,
    /// Size and type of the failed message's header.
    bad_header: Option<(u16, u8)>,
    scan: u64,
}

/// What a `D` message of one `msg_id` looks like: the payload sizes accepted, as message
/// sizes (`2 + data`; an empty range if the id is not subscribed), and for the fast path the
/// subscription's index and where its `uint64_t` timestamp is: one table lookup a row.
#[derive(Debug, Clone, Copy)]
struct DataKind {
    min: u16,
    max: u16,
    sub: u32,
    /// Offset of the `uint64_t` timestamp in the data, or [`NO_U64_TIMESTAMP`].
    timestamp: u16,
}

/// A subscription without a `uint64_t` timestamp: its rows take the general path.
const NO_U64_TIMESTAMP: u16 = u16::MAX;

const UNSUBSCRIBED: DataKind = DataKind {
    min: u16::MAX,
    max: 0,
    sub: 0,
    timestamp: NO_U64_TIMESTAMP,
};

/// A run of the fast path in progress ([`Framer::run_start`]): where it is in the window and
/// what it has taken, kept by the caller (in registers) until [`Framer::run_end`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct FastRun {
    /// Index of the next message in the window.
    p: usize,
    /// Where taken messages must end ([`Framer::end_max`]).
    end_max: usize,
    /// Index before which messages must start.
    stop: usize,
    /// Whether to fetch the bytes ahead into the cache.
    ahead: bool,
    /// Index of the last message taken.
    last: Option<usize>,
    /// The largest timestamp taken.
    latest: u64,
}

/// A `D` message the fast path takes ([`Framer::peek_data`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PeekedRow {
    /// Index of the message header in the window.
    pub(crate) at: usize,
    /// Payload size (msg_id included).
    pub(crate) size: usize,
    /// The subscription.
    pub(crate) sub: usize,
    /// The row's timestamp.
    pub(crate) timestamp: u64,
}

#[derive(Clone)]
pub(crate) struct Framer {
    pos: u64,
    prev: Option<u64>,
    floor: u64,
    segment_end: u64,
    segments: Vec<u64>,
    notices: Vec<Frame>,
    resync: Option<Resync>,
    d_kinds: Vec<DataKind>,
}

impl Framer {
    pub(crate) fn new() -> Framer {
        Framer {
            pos: HEADER_LEN as u64,
            prev: None,
            floor: HEADER_LEN as u64,
            segment_end: u64::MAX,
            segments: Vec::new(),
            notices: Vec::new(),
            resync: None,
            d_kinds: vec![UNSUBSCRIBED; 1 << 16],
        }
    }

    /// Declares `msg_id` subscribed as subscription `sub` with data payloads of `min..=max`
    /// bytes (`None`: rows that cannot be decoded) and a `uint64_t` timestamp at this offset
    /// of the data, if it has one.
    pub(crate) fn subscribe(
        &mut self,
        msg_id: u16,
        sizes: Option<(usize, usize)>,
        sub: usize,
        u64_timestamp: Option<usize>,
    ) {
        let to_size = |n: usize| u16::try_from(n + 2).unwrap_or(u16::MAX);
        self.d_kinds[usize::from(msg_id)] = match sizes {
            Some((min, max)) => DataKind {
                min: to_size(min),
                max: to_size(max),
                sub: u32::try_from(sub).unwrap_or(u32::MAX),
                timestamp: u64_timestamp
                    .and_then(|t| u16::try_from(t).ok())
                    .unwrap_or(NO_U64_TIMESTAMP),
            },
            None => UNSUBSCRIBED,
        };
    }

    /// Fast path: the `D` message at the current position if it is strongly plausible,
    /// whole in the window `[base, base + w.len())` and of a subscription with a `uint64_t`
    /// timestamp, without moving; [`Framer::commit`] then accepts it. `None` means "take the
    /// general path".
    #[inline]
    pub(crate) fn peek_data(&self, w: &[u8], base: u64) -> Option<PeekedRow> {
        if self.resync.is_some() || !self.notices.is_empty() {
            return None;
        }
        let p = usize::try_from(self.pos.checked_sub(base)?).ok()?;
        self.data_at(w, p, self.end_max(w, base))
    }

    /// The fast path over a run of messages: from the current position, every `D` message
    /// [`Framer::peek_data`] would accept, that starts before `limit`, is given to `f` and
    /// accepted, until one is not or `f` returns `false` (after the row it was given).
    /// Returns the largest timestamp given (0 if none). The checks that hold for the whole
    /// run are made once, and the position is kept in a register meanwhile.
    #[inline]
    pub(crate) fn data_run(
        &mut self,
        w: &[u8],
        base: u64,
        limit: u64,
        mut f: impl FnMut(PeekedRow) -> bool,
    ) -> u64 {
        let Some(mut run) = self.run_start(w, base, limit) else {
            return 0;
        };
        while let Some(row) = self.run_next(&mut run, w) {
            if !f(row) {
                break;
            }
        }
        self.run_end(run, base)
    }

    /// Starts a run of the fast path at the current position ([`Framer::data_run`], one row
    /// at a time: [`Framer::run_next`], then [`Framer::run_end`]), or `None` if the fast path
    /// does not apply here (mid-recovery, notices to report, the position outside the window).
    #[inline]
    pub(crate) fn run_start(&self, w: &[u8], base: u64, limit: u64) -> Option<FastRun> {
        if self.resync.is_some() || !self.notices.is_empty() {
            return None;
        }
        let p = usize::try_from(self.pos.checked_sub(base)?).ok()?;
        Some(FastRun {
            p,
            end_max: self.end_max(w, base),
            stop: usize::try_from(limit.saturating_sub(base)).unwrap_or(usize::MAX),
            // A walk through a file in memory reads it in order, but each message's header
            // is found only once the one before is read: the bytes a little ahead are
            // fetched before they are needed (the hardware's prefetcher stops at each 4 KiB
            // page). A stream's window was just copied in, and is in the cache already.
            ahead: w.len() > PREFETCH_MIN_WINDOW,
            last: None,
            latest: 0,
        })
    }

    /// The run's next row, taken (`None`: the run ends here; the framer's position moves
    /// only at [`Framer::run_end`]). `w` is the window the run started in.
    #[inline(always)]
    pub(crate) fn run_next(&self, run: &mut FastRun, w: &[u8]) -> Option<PeekedRow> {
        if run.p >= run.stop {
            return None;
        }
        if run.ahead {
            crate::read::log::prefetch(w, (run.p + PREFETCH_AHEAD) as u64, 1);
        }
        let row = self.data_at(w, run.p, run.end_max)?;
        run.latest = run.latest.max(row.timestamp);
        run.last = Some(run.p);
        run.p = row.at + MESSAGE_HEADER_LEN + row.size;
        Some(row)
    }

    /// Ends a run: the position moves past its rows. Returns the largest timestamp of its
    /// rows (0 if none).
    #[inline]
    pub(crate) fn run_end(&mut self, run: FastRun, base: u64) -> u64 {
        if let Some(l) = run.last {
            self.prev = Some(base + l as u64);
            self.pos = base + run.p as u64;
        }
        run.latest
    }

    /// Where messages of the window `[base, base + w.len())` must end to be taken by the
    /// fast path: within the window and within the data segment.
    fn end_max(&self, w: &[u8], base: u64) -> usize {
        let segment = usize::try_from(self.segment_end.saturating_sub(base)).unwrap_or(usize::MAX);
        w.len().min(segment)
    }

    /// The fast path's row at index `p` of the window: a strongly plausible `D` message of a
    /// subscription with a `uint64_t` timestamp, ending by `end_max`.
    #[inline(always)]
    fn data_at(&self, w: &[u8], p: usize, end_max: usize) -> Option<PeekedRow> {
        let h = w.get(p..p + MESSAGE_HEADER_LEN + 2)?;
        if h[2] != b'D' {
            return None;
        }
        let size = u16::from_le_bytes([h[0], h[1]]);
        let kind = self.d_kinds[usize::from(u16::from_le_bytes([h[3], h[4]]))];
        let end = p + MESSAGE_HEADER_LEN + usize::from(size);
        if !(kind.min <= size
            && size <= kind.max
            && kind.timestamp != NO_U64_TIMESTAMP
            && end <= end_max)
        {
            return None;
        }
        // Accepted rows hold the timestamp: it lies before any trailing padding.
        let at = p + MESSAGE_HEADER_LEN + 2 + usize::from(kind.timestamp);
        let timestamp = u64::from_le_bytes(w.get(at..at + 8)?.try_into().ok()?);
        Some(PeekedRow {
            at: p,
            size: usize::from(size),
            sub: kind.sub as usize,
            timestamp,
        })
    }

    /// The start of the next message.
    pub(crate) fn pos(&self) -> u64 {
        self.pos
    }

    /// The start of the last message accepted.
    pub(crate) fn prev(&self) -> Option<u64> {
        self.prev
    }

    /// Whether the framer is mid-recovery or has notices to report.
    pub(crate) fn is_busy(&self) -> bool {
        self.resync.is_some() || !self.notices.is_empty()
    }

    /// Whether the file has appended data segments still ahead.
    pub(crate) fn has_segments(&self) -> bool {
        !self.segments.is_empty() || self.segment_end != u64::MAX
    }

    /// Continues from `pos` as if the message at `prev` had just been accepted.
    pub(crate) fn resume_at(&mut self, pos: u64, prev: Option<u64>) {
        self.pos = pos;
        self.prev = prev;
        self.floor = self.floor.max(prev.map_or(pos, |p| p + 1));
        self.resync = None;
    }

    /// The first offset in `from..from + max_scan` where `chain` consecutive strongly
    /// plausible messages start, in the window `[base, base + w.len())` of the file (whole
    /// to its end if the window reaches it): a message boundary beyond doubt. A chain that
    /// runs out of the window is not one.
    pub(crate) fn find_boundary(
        &self,
        w: &[u8],
        base: u64,
        from: u64,
        max_scan: usize,
        chain: usize,
    ) -> Option<u64> {
        let end = w
            .len()
            .min(usize::try_from(self.segment_end.saturating_sub(base)).unwrap_or(usize::MAX));
        let from = usize::try_from(from.checked_sub(base)?).ok()?;
        (from..end.min(from.saturating_add(max_scan)))
            .find(|&q| {
                let mut at = q;
                (0..chain).all(|_| {
                    let Some(h) = w.get(at..at + MESSAGE_HEADER_LEN) else {
                        return false;
                    };
                    let next = at + MESSAGE_HEADER_LEN + usize::from(u16_at(h, 0));
                    let strong = next <= end
                        && self.plausibility(
                            base + at as u64,
                            h[2],
                            &w[at + MESSAGE_HEADER_LEN..next],
                        ) == Plausibility::Strong;
                    at = next;
                    strong
                })
            })
            .map(|q| base + q as u64)
    }

    /// Accepts the message found by [`Framer::peek_data`] (`offset` in the file).
    #[inline]
    pub(crate) fn commit(&mut self, offset: u64, size: usize) {
        self.prev = Some(offset);
        self.pos = offset + (MESSAGE_HEADER_LEN + size) as u64;
    }

    /// The next frame of the window `[base, base + w.len())`; `eof` says the window reaches the
    /// end of the file.
    pub(crate) fn next(&mut self, w: &[u8], base: u64, eof: bool) -> Frame {
        if let Some(n) = self.notices.pop() {
            return n;
        }
        let avail = base + w.len() as u64;
        loop {
            let end = if eof {
                self.segment_end.min(avail)
            } else {
                self.segment_end
            };
            if let Some(rs) = self.resync {
                return self.scan(w, base, avail, end, rs);
            }
            let p = self.pos;
            if p >= end {
                if end == self.segment_end && !self.segments.is_empty() {
                    let next = self.segments.remove(0);
                    self.segment_end = self.segments.first().copied().unwrap_or(u64::MAX);
                    self.pos = next;
                    self.floor = next;
                    self.prev = None;
                    continue;
                }
                if p > end && eof && end == avail {
                    self.pos = end;
                    return Frame::BadAppendedOffset { offset: p };
                }
                if eof && !self.segments.is_empty() {
                    // Segments that start beyond the end of the file.
                    let offset = self.segments.remove(0);
                    self.segment_end = self.segments.first().copied().unwrap_or(u64::MAX);
                    return Frame::BadAppendedOffset { offset };
                }
                return Frame::End;
            }
            if p + MESSAGE_HEADER_LEN as u64 > end {
                self.pos = end;
                return Frame::Truncated {
                    offset: p,
                    declared: None,
                    available: end - p,
                };
            }
            let Some(h) = window(w, base, p, MESSAGE_HEADER_LEN) else {
                return self.need_more(p);
            };
            let size = u16_at(h, 0);
            let ty = h[2];
            let msg_end = p + MESSAGE_HEADER_LEN as u64 + u64::from(size);
            if msg_end > end {
                self.fail(p, Some((size, ty)));
                continue;
            }
            let Some(msg) = window(w, base, p, MESSAGE_HEADER_LEN + usize::from(size)) else {
                return self.need_more(p);
            };
            // A weak message needs a plausible next header; a message of an unknown type (a
            // newer writer's, or garbage) needs a next message that is strongly plausible.
            let accepted = match self.plausibility(p, ty, &msg[MESSAGE_HEADER_LEN..]) {
                Plausibility::Strong => true,
                Plausibility::Invalid => false,
                // A row of a subscribed format whose declared size does not fit it: a
                // damaged size field when the format's own size ends on a message (even
                // when the declared size does too: following it would lose every message
                // it spans). Then the boundary is the format's: the scan resumes there,
                // and only this row is lost.
                Plausibility::Weak
                    if ty == b'D'
                        && let Some(ends) = self.format_ends(&msg[MESSAGE_HEADER_LEN..], p) =>
                {
                    let strong_at = |at: u64| self.strong_successor(w, base, avail, end, at);
                    let (Some(a), Some(b)) = (strong_at(ends.0), strong_at(ends.1)) else {
                        return self.need_more(p);
                    };
                    if a || b {
                        false
                    } else {
                        match self.successor(w, base, avail, end, msg_end) {
                            None => return self.need_more(p),
                            Some(next) => matches!(next, Plausibility::Strong | Plausibility::Weak),
                        }
                    }
                }
                Plausibility::Weak => match self.successor(w, base, avail, end, msg_end) {
                    None => return self.need_more(p),
                    Some(next) => matches!(next, Plausibility::Strong | Plausibility::Weak),
                },
                Plausibility::Unknown => {
                    match self.strong_successor(w, base, avail, end, msg_end) {
                        None => return self.need_more(p),
                        Some(strong) => strong,
                    }
                }
            };
            if !accepted {
                self.fail(p, Some((size, ty)));
                continue;
            }
            self.prev = Some(p);
            self.pos = msg_end;
            if ty == b'B' && p == HEADER_LEN as u64 {
                self.read_flag_bits(&msg[MESSAGE_HEADER_LEN..], msg_end);
            }
            return Frame::Message {
                offset: p,
                ty,
                size,
            };
        }
    }

    /// Where a `D` message at `at` of a subscribed `msg_id` would end with its format's
    /// sizes (without and with trailing padding), if the `msg_id` is subscribed with
    /// readable rows.
    fn format_ends(&self, payload: &[u8], at: u64) -> Option<(u64, u64)> {
        let kind = self.d_kinds[usize::from(u16_at(payload, 0))];
        (kind.min <= kind.max).then(|| {
            let end = |size: u16| at + MESSAGE_HEADER_LEN as u64 + u64::from(size);
            (end(kind.min), end(kind.max))
        })
    }

    fn need_more(&self, p: u64) -> Frame {
        let keep_from = match self.prev {
            Some(prev) => (prev + 1).max(self.floor).min(p),
            None => p,
        };
        Frame::NeedMore { keep_from }
    }

    fn fail(&mut self, bad: u64, bad_header: Option<(u16, u8)>) {
        let scan = self.prev.map_or(bad + 1, |prev| prev + 1).max(self.floor);
        self.resync = Some(Resync {
            bad,
            bad_header,
            scan,
        });
    }

    /// How plausible the header at `msg_end` is, judged from its 3 bytes alone; `Strong`
    /// stands for "the segment or file ends exactly here". `None`: bytes are missing.
    fn successor(
        &self,
        w: &[u8],
        base: u64,
        avail: u64,
        end: u64,
        at: u64,
    ) -> Option<Plausibility> {
        if at == end {
            return Some(Plausibility::Strong);
        }
        if at + MESSAGE_HEADER_LEN as u64 > end {
            return Some(Plausibility::Invalid);
        }
        if at + MESSAGE_HEADER_LEN as u64 > avail {
            return None;
        }
        let h = window(w, base, at, MESSAGE_HEADER_LEN)?;
        Some(header_plausibility(h))
    }

    /// Whether the message at `at` is strongly plausible as a whole (or the data ends exactly
    /// there). `None`: bytes are missing.
    fn strong_successor(&self, w: &[u8], base: u64, avail: u64, end: u64, at: u64) -> Option<bool> {
        if at == end {
            return Some(true);
        }
        if at + MESSAGE_HEADER_LEN as u64 > end {
            return Some(false);
        }
        let h = window(w, base, at, MESSAGE_HEADER_LEN)
            .or_else(|| (avail >= end).then_some(&[][..]))?;
        if h.is_empty() {
            return Some(false);
        }
        let size = u16_at(h, 0);
        let next_end = at + MESSAGE_HEADER_LEN as u64 + u64::from(size);
        if next_end > end {
            return Some(false);
        }
        let msg = window(w, base, at, MESSAGE_HEADER_LEN + usize::from(size))?;
        Some(self.plausibility(at, h[2], &msg[MESSAGE_HEADER_LEN..]) == Plausibility::Strong)
    }

    fn plausibility(&self, offset: u64, ty: u8, p: &[u8]) -> Plausibility {
        let Some(kind) = MessageType::from_byte(ty) else {
            return if p.is_empty() {
                Plausibility::Invalid
            } else {
                Plausibility::Unknown
            };
        };
        if p.len() < kind.min_size() {
            return Plausibility::Invalid;
        }
        let strong = match kind {
            MessageType::Data => {
                let kind = self.d_kinds[usize::from(u16_at(p, 0))];
                let size = p.len() as u16;
                kind.min <= size && size <= kind.max
            }
            MessageType::Sync => p[..8] == SYNC_MAGIC,
            MessageType::FlagBits => offset == HEADER_LEN as u64,
            MessageType::Format => plausible_format(p),
            MessageType::Info | MessageType::Parameter => plausible_key(p),
            MessageType::MultiInfo => p[0] <= 1 && plausible_key(&p[1..]),
            MessageType::DefaultParameter => (1..=3).contains(&p[0]) && plausible_key(&p[1..]),
            MessageType::Subscribe => p[3..].iter().all(|&c| plausible_name_byte(c)),
            MessageType::Unsubscribe | MessageType::Dropout => p.len() == 2,
            MessageType::Logging | MessageType::TaggedLogging => {
                matches!(p[0], b'0'..=b'7' | 0..=7)
            }
        };
        if strong {
            Plausibility::Strong
        } else {
            Plausibility::Weak
        }
    }

    /// Learns the appended-data segments from the flag bits at offset 16.
    fn read_flag_bits(&mut self, p: &[u8], after: u64) {
        let Ok(super::message::Message::FlagBits(bits)) = super::message::Message::parse(b'B', p)
        else {
            return;
        };
        if !bits.has_data_appended() {
            return;
        }
        let mut last = after;
        for offset in bits.appended() {
            if offset < last {
                self.notices.push(Frame::BadAppendedOffset { offset });
            } else {
                self.segments.push(offset);
                last = offset;
            }
        }
        // The main data ends where the first appended segment starts.
        self.segment_end = self.segments.first().copied().unwrap_or(u64::MAX);
    }

    fn scan(&mut self, w: &[u8], base: u64, avail: u64, end: u64, rs: Resync) -> Frame {
        let mut q = rs.scan;
        loop {
            if q + MESSAGE_HEADER_LEN as u64 > end {
                self.resync = None;
                self.pos = end;
                return match rs.bad_header {
                    Some((size, ty))
                        if rs.bad + MESSAGE_HEADER_LEN as u64 + u64::from(size) > end
                            && MessageType::from_byte(ty).is_some() =>
                    {
                        Frame::Truncated {
                            offset: rs.bad,
                            declared: Some(size),
                            available: end.saturating_sub(rs.bad + MESSAGE_HEADER_LEN as u64),
                        }
                    }
                    _ => Frame::Skipped {
                        from: rs.bad,
                        to: end,
                    },
                };
            }
            let Some(h) = window(w, base, q, MESSAGE_HEADER_LEN) else {
                self.resync = Some(Resync { scan: q, ..rs });
                return Frame::NeedMore { keep_from: q };
            };
            if h[0] == SYNC_MAGIC[0] {
                match window(w, base, q, SYNC_MAGIC.len()) {
                    Some(m) if m == SYNC_MAGIC => {
                        let after = q + SYNC_MAGIC.len() as u64;
                        if after > rs.bad && after <= end {
                            return self.found(after, rs);
                        }
                    }
                    None if q + SYNC_MAGIC.len() as u64 <= end => {
                        self.resync = Some(Resync { scan: q, ..rs });
                        return Frame::NeedMore { keep_from: q };
                    }
                    _ => {}
                }
            }
            if header_plausibility(h) != Plausibility::Invalid
                && MessageType::from_byte(h[2]).is_some()
            {
                let size = u16_at(h, 0);
                let cand_end = q + MESSAGE_HEADER_LEN as u64 + u64::from(size);
                if cand_end <= end {
                    let Some(msg) = window(w, base, q, MESSAGE_HEADER_LEN + usize::from(size))
                    else {
                        self.resync = Some(Resync { scan: q, ..rs });
                        return Frame::NeedMore { keep_from: q };
                    };
                    if self.plausibility(q, h[2], &msg[MESSAGE_HEADER_LEN..])
                        == Plausibility::Strong
                    {
                        match self.successor(w, base, avail, end, cand_end) {
                            None => {
                                self.resync = Some(Resync { scan: q, ..rs });
                                return Frame::NeedMore { keep_from: q };
                            }
                            Some(Plausibility::Weak | Plausibility::Strong) => {
                                return self.found(q, rs);
                            }
                            Some(_) => {}
                        }
                    }
                }
            }
            q += 1;
        }
    }

    fn found(&mut self, at: u64, rs: Resync) -> Frame {
        self.resync = None;
        self.pos = at;
        self.floor = at + 1;
        if at > rs.bad {
            Frame::Skipped {
                from: rs.bad,
                to: at,
            }
        } else {
            Frame::Overlap {
                prev: self.prev.unwrap_or(rs.bad),
                next: at,
            }
        }
    }
}

/// Judges a message header from its 3 bytes: known type and big enough.
fn header_plausibility(h: &[u8]) -> Plausibility {
    match MessageType::from_byte(h[2]) {
        Some(kind) if usize::from(u16_at(h, 0)) >= kind.min_size() => Plausibility::Weak,
        Some(_) => Plausibility::Invalid,
        None if u16_at(h, 0) > 0 && h[2] != 0 => Plausibility::Unknown,
        None => Plausibility::Invalid,
    }
}

fn plausible_name_byte(c: u8) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, b'_' | b'-' | b'/')
}

/// `name:...;` with a plausible name.
fn plausible_format(p: &[u8]) -> bool {
    let Some(colon) = p.iter().position(|&c| c == b':') else {
        return false;
    };
    colon > 0 && p[..colon].iter().all(|&c| plausible_name_byte(c)) && p.last() == Some(&b';')
}

/// `key_len`, then a printable key containing a space (`type name`).
fn plausible_key(p: &[u8]) -> bool {
    let key_len = usize::from(p[0]);
    key_len >= 3
        && key_len < p.len()
        && p[1..=key_len]
            .iter()
            .all(|&c| c.is_ascii_graphic() || c == b' ')
        && p[1..=key_len].contains(&b' ')
}

/// The bytes `[at, at + len)` of the window, if it holds them.
fn window(w: &[u8], base: u64, at: u64, len: usize) -> Option<&[u8]> {
    let start = usize::try_from(at.checked_sub(base)?).ok()?;
    w.get(start..start.checked_add(len)?)
}
