//! Streaming over any `io::Read`: memory stays bounded by a few messages plus the definitions,
//! whatever the file size.

use std::io::Read;

use super::message::{FileHeader, HEADER_LEN, MessageType};
use super::metadata::Applied;
use super::window::{Reading, Window};
use super::{
    Diagnostic, Dropout, FastRow, FastRun, LoggedMessage, Metadata, ParameterChange, ReadError,
    Row, Step, Subscription, Walker,
};
use crate::typed::{Topic, TypedDecoder, TypedError};

/// One thing read from a stream.
#[derive(Debug, Clone)]
pub enum Event<'a> {
    /// A definition was read (`B`, `F`, `I`, `M`, `Q`, `R`, or `P` before the data section);
    /// [`StreamReader::metadata`] has it. Never a `D`: the rows of a subscription that cannot
    /// be decoded are skipped, said once by the subscription's diagnostic. A definition kept
    /// despite something odd (a format outside the grammar, a value kept as far as it goes)
    /// is this event, then an [`Event::Diagnostic`] that says what is odd; a definition left
    /// out is only the diagnostic.
    Definition {
        /// File offset of the message.
        offset: u64,
        /// Its type.
        ty: MessageType,
    },
    /// A new subscription.
    Subscription(&'a Subscription),
    /// A data row.
    Row(Row<'a>),
    /// A logged string.
    Logged(LoggedMessage),
    /// A parameter changed.
    ParameterChange(ParameterChange),
    /// Logging lost data.
    Dropout(Dropout),
    /// A sync message.
    Sync {
        /// Its file offset.
        offset: u64,
    },
    /// Something wrong or unusual; reading goes on. (Boxed: rare, and it would make every
    /// event as large as the largest diagnostic.)
    Diagnostic(Box<Diagnostic>),
}

/// Reads a ULog file from any `io::Read`, one event at a time.
///
/// ```no_run
/// # fn main() -> Result<(), ulog_runtime::ReadError> {
/// use ulog_runtime::{Event, StreamReader};
/// let file = std::io::BufReader::new(std::fs::File::open("flight.ulg")?);
/// let mut reader = StreamReader::new(file)?;
/// let mut rows = 0;
/// while let Some(event) = reader.next_event()? {
///     match event {
///         Event::Row(_) => rows += 1,
///         Event::Diagnostic(d) => eprintln!("{d}"),
///         _ => {}
///     }
/// }
/// println!("{rows} rows");
/// # Ok(()) }
/// ```
pub struct StreamReader<R> {
    /// The bytes read and held.
    win: Window<Reading<R>>,
    walker: Walker,
    /// A diagnostic to report before the next message (boxed: checked on every row).
    pending: Option<Box<Diagnostic>>,
    /// A second one, reported after `pending` (a subscription can have two).
    pending_next: Option<Box<Diagnostic>>,
    /// The message behind the last event: its offset, type and the range of its payload in
    /// `buf` (valid until the next read moves the window).
    last: Option<(u64, u8, std::ops::Range<usize>)>,
}

/// What [`StreamReader::advance`] moved to: an event without its borrows of the reader.
enum Next {
    Row {
        offset: u64,
        /// The row's data in `buf`.
        data: std::ops::Range<usize>,
        sub: usize,
        timestamp: u64,
    },
    Definition {
        offset: u64,
        ty: MessageType,
    },
    /// The last subscription.
    Subscription,
    Diagnostic(Box<Diagnostic>),
    /// An event that borrows nothing.
    Event(Event<'static>),
}

/// One message as the file holds it ([`StreamReader::message`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawMessage<'a> {
    /// File offset of its header.
    pub offset: u64,
    /// Its type byte (`b'F'`, `b'D'`...).
    pub ty: u8,
    /// Its payload, the bytes after the 3-byte header.
    pub payload: &'a [u8],
}

impl<R: Read> StreamReader<R> {
    /// Reads the file header and prepares to read messages.
    pub fn new(mut input: R) -> Result<StreamReader<R>, ReadError> {
        let mut header = [0u8; HEADER_LEN];
        let mut got = 0;
        while got < HEADER_LEN {
            match input.read(&mut header[got..]) {
                Ok(0) => break,
                Ok(n) => got += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
        let header = FileHeader::parse(&header[..got])?;
        let walker = Walker::new(header);
        let pending = walker.meta.header_diagnostic().map(Box::new);
        Ok(StreamReader {
            win: Window::new(Reading(input), HEADER_LEN as u64),
            walker,
            pending,
            pending_next: None,
            last: None,
        })
    }

    /// The message the last event of [`StreamReader::next_event`] came from, as the file
    /// holds it (`None` after a diagnostic, which stands for no message, and before the
    /// first event): what a tool that copies or rewrites messages writes back unchanged.
    /// Call it once the event is no longer used (the event borrows the reader).
    ///
    /// ```no_run
    /// # fn main() -> Result<(), ulog_runtime::ReadError> {
    /// use ulog_runtime::{Event, StreamReader};
    /// let file = std::io::BufReader::new(std::fs::File::open("flight.ulg")?);
    /// let mut reader = StreamReader::new(file)?;
    /// while let Some(event) = reader.next_event()? {
    ///     let is_format = matches!(event, Event::Definition { ty: ulog_runtime::read::MessageType::Format, .. });
    ///     if is_format {
    ///         let raw = reader.message().expect("a message");
    ///         println!("{}", String::from_utf8_lossy(raw.payload));
    ///     }
    /// }
    /// # Ok(()) }
    /// ```
    pub fn message(&self) -> Option<RawMessage<'_>> {
        let (offset, ty, range) = self.last.clone()?;
        Some(RawMessage {
            offset,
            ty,
            payload: &self.win.buf[range],
        })
    }

    /// Reads a log's header and definitions section, without the rows: the formats, info,
    /// multi info and initial parameters (PX4's definitions are tens to hundreds of
    /// kilobytes, mostly parameters, whatever the log's size). It stops after the first
    /// message of the data section (a subscription, row, logged string, dropout, parameter
    /// change...), which it has read: a first subscription is in the metadata. What a tool
    /// checks before a pass, e.g. that the topics a user asked for are there. A format
    /// defined after the data began (PX4 never writes one; the whole-file reader takes it)
    /// is not seen.
    ///
    /// ```no_run
    /// # fn main() -> Result<(), ulog_runtime::ReadError> {
    /// use ulog_runtime::StreamReader;
    /// let file = std::io::BufReader::new(std::fs::File::open("flight.ulg")?);
    /// let definitions = StreamReader::read_definitions(file)?;
    /// println!("{} formats", definitions.schema().formats().len());
    /// # Ok(()) }
    /// ```
    pub fn read_definitions(input: R) -> Result<Metadata, ReadError> {
        let mut reader = StreamReader::new(input)?;
        while !reader.walker.meta.in_data_section() {
            if reader.next_event()?.is_none() {
                break;
            }
        }
        Ok(reader.walker.meta)
    }

    /// Bytes the reader holds for its window of the file: bounded by a few messages
    /// (at most a few hundred kilobytes), whatever the file size.
    pub fn buffered_capacity(&self) -> usize {
        self.win.buf.capacity()
    }

    /// The input.
    pub fn get_ref(&self) -> &R {
        &self.win.input.0
    }

    /// The input. Reading from it directly takes bytes the reader has not seen: do it only
    /// when the reader is done with it (after [`StreamReader::next_event`] gave `None`).
    pub fn get_mut(&mut self) -> &mut R {
        &mut self.win.input.0
    }

    /// Everything read so far but the data rows.
    pub fn metadata(&self) -> &Metadata {
        &self.walker.meta
    }

    /// A checked decoder for topic `T` against the formats read so far: make it once the
    /// definitions are read, e.g. at the topic's [`Event::Subscription`], then decode its rows
    /// with [`TypedDecoder::decode_row`].
    ///
    /// ```no_run
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use ulog_runtime::{Event, StreamReader, ULog};
    ///
    /// #[derive(ULog)]
    /// struct VehicleAttitude { timestamp: u64, q: [f32; 4] }
    ///
    /// let file = std::io::BufReader::new(std::fs::File::open("flight.ulg")?);
    /// let mut reader = StreamReader::new(file)?;
    /// let mut decoder = None;
    /// while let Some(event) = reader.next_event()? {
    ///     match event {
    ///         Event::Subscription(s) if s.name == "vehicle_attitude" && decoder.is_none() => {
    ///             decoder = Some(reader.typed::<VehicleAttitude>()?);
    ///         }
    ///         Event::Row(row) => {
    ///             if let Some(att) = decoder.as_ref().and_then(|d| d.decode_row(&row)) {
    ///                 println!("{} {:?}", att.timestamp, att.q);
    ///             }
    ///         }
    ///         _ => {}
    ///     }
    /// }
    /// # Ok(()) }
    /// ```
    ///
    /// Made before the definitions are all read, without the format among those read so far,
    /// it fails with [`TypedError::DefinitionsNotRead`].
    pub fn typed<T: Topic>(&self) -> Result<TypedDecoder<T>, TypedError> {
        TypedDecoder::new(self.metadata().schema()).map_err(|e| self.too_early(e))
    }

    /// [`StreamReader::typed`] for the topic named `topic`, read as `T` (one type for the
    /// topics that share a layout: see [`Log::topic_as`](crate::Log::topic_as)).
    pub fn typed_as<T: Topic>(&self, topic: &str) -> Result<TypedDecoder<T>, TypedError> {
        TypedDecoder::new_as(self.metadata().schema(), topic).map_err(|e| self.too_early(e))
    }

    /// A format not found while the definitions are still being read (and more may come):
    /// said so.
    fn too_early(&self, e: TypedError) -> TypedError {
        match e {
            TypedError::NoSuchTopic {
                topic, rust_type, ..
            } if !self.walker.meta.in_data_section() && !self.win.eof => {
                TypedError::DefinitionsNotRead {
                    topic,
                    rust_type,
                    read: self.metadata().schema().formats().len(),
                }
            }
            e => e,
        }
    }

    /// Calls `f` with every event to the end of the file: what a loop over
    /// [`StreamReader::next_event`] does, with the rows of each window of the file handed
    /// over in a tight loop (the fastest way through a stream).
    ///
    /// ```no_run
    /// # fn main() -> Result<(), ulog_runtime::ReadError> {
    /// use ulog_runtime::{Event, StreamReader};
    /// let file = std::io::BufReader::new(std::fs::File::open("flight.ulg")?);
    /// let mut rows = 0;
    /// StreamReader::new(file)?.for_each_event(|event| {
    ///     if let Event::Row(_) = event {
    ///         rows += 1;
    ///     }
    /// })?;
    /// # Ok(()) }
    /// ```
    pub fn for_each_event(&mut self, mut f: impl FnMut(Event<'_>)) -> Result<(), ReadError> {
        // `f` is called from one place, so that the compiler can put it inline in the loop
        // over a window's rows: a call made for each row costs more than decoding a small
        // row. The rows of the current window come as long as they come (a run of the fast
        // path, its position kept here); then one event of the general path, and again.
        let mut run = None;
        loop {
            let event = match self.run_row(&mut run) {
                Some(row) => Event::Row(Row {
                    timestamp: row.timestamp,
                    offset: row.offset,
                    data: &self.win.bytes()[row.data],
                    subscription: &self.walker.meta.subscriptions[row.sub],
                    schema: &self.walker.meta.schema,
                }),
                None => {
                    self.end_run(&mut run);
                    match self.next_event()? {
                        Some(event) => event,
                        None => return Ok(()),
                    }
                }
            };
            f(event);
        }
    }

    /// The next event, or `None` at the end of the file. In a hot loop, match the event by
    /// reference (`match &event`): moving the row out of it copies it through memory the
    /// processor has just written, which costs more than decoding a small row.
    #[allow(clippy::should_implement_trait)]
    pub fn next_event(&mut self) -> Result<Option<Event<'_>>, ReadError> {
        Ok(self.advance()?.map(|next| self.event(next)))
    }

    /// Calls `f` with every event, the message it came from as the file holds it (`None`
    /// for a diagnostic) and the metadata read so far, to the end of the file or the first
    /// error `f` returns: what a tool that copies or rewrites a log needs (the rows of each
    /// window come in a tight loop, as with [`StreamReader::for_each_event`]). After an error,
    /// the reader stands after the message `f` refused: a later read goes on from there.
    ///
    /// ```no_run
    /// # fn main() -> Result<(), ulog_runtime::ReadError> {
    /// use std::io::Write;
    /// use ulog_runtime::StreamReader;
    /// let file = std::fs::File::open("flight.ulg")?;
    /// let mut out = std::io::BufWriter::new(std::fs::File::create("copy.ulg")?);
    /// out.write_all(&StreamReader::new(std::fs::File::open("flight.ulg")?)?.metadata().header().to_bytes())?;
    /// StreamReader::new(file)?.for_each_message(|_meta, _event, raw| {
    ///     if let Some(m) = raw {
    ///         let size = (m.payload.len() as u16).to_le_bytes();
    ///         out.write_all(&[size[0], size[1], m.ty])?;
    ///         out.write_all(m.payload)?;
    ///     }
    ///     Ok::<(), ulog_runtime::ReadError>(())
    /// })?;
    /// # Ok(()) }
    /// ```
    pub fn for_each_message<E: From<ReadError>>(
        &mut self,
        mut f: impl FnMut(&Metadata, Event<'_>, Option<RawMessage<'_>>) -> Result<(), E>,
    ) -> Result<(), E> {
        // `f` is called from one place, as in `for_each_event`.
        let mut run = None;
        loop {
            let (event, raw) = match self.run_row(&mut run) {
                Some(row) => {
                    // The metadata is the caller's to read at each row: its latest timestamp
                    // includes the row's, as off the fast path.
                    self.walker.meta.saw_timestamp(row.timestamp);
                    let window = self.win.bytes();
                    let raw = RawMessage {
                        offset: row.offset,
                        ty: b'D',
                        payload: &window[row.data.start - 2..row.data.end],
                    };
                    let event = Event::Row(Row {
                        timestamp: row.timestamp,
                        offset: row.offset,
                        data: &window[row.data],
                        subscription: &self.walker.meta.subscriptions[row.sub],
                        schema: &self.walker.meta.schema,
                    });
                    (event, Some(raw))
                }
                None => {
                    self.end_run(&mut run);
                    let Some(next) = self.advance()? else {
                        return Ok(());
                    };
                    (self.event(next), self.message())
                }
            };
            if let Err(e) = f(&self.walker.meta, event, raw) {
                // The rows given so far are read: a later call goes on after them.
                self.end_run(&mut run);
                return Err(e);
            }
        }
    }

    /// The next row of the fast path in the current window: of the run `run`, started where
    /// the reader stands if there is none (after an event of the general path). `None`: the
    /// run ends here, and the caller ends it ([`StreamReader::end_run`]) before reading on.
    #[inline(always)]
    fn run_row(&self, run: &mut Option<FastRun>) -> Option<FastRow> {
        if run.is_none() {
            *run = match self.pending {
                None => self.walker.run_start(self.win.bytes(), self.win.base),
                Some(_) => None,
            };
        }
        self.walker
            .run_next(run.as_mut()?, self.win.bytes(), self.win.base)
    }

    /// Ends the run of fast rows, if one is under way: the reader stands after its rows.
    #[inline]
    fn end_run(&mut self, run: &mut Option<FastRun>) {
        if let Some(r) = run.take() {
            self.walker.run_end(r, self.win.base);
        }
    }

    /// Moves to the next event, recording its message.
    fn advance(&mut self) -> Result<Option<Next>, ReadError> {
        if let Some(d) = self.pending.take() {
            self.pending = self.pending_next.take();
            self.last = None;
            return Ok(Some(Next::Diagnostic(d)));
        }
        let (start, end) = (self.win.start, self.win.end);
        if let Some(row) = self
            .walker
            .fast_row(&self.win.buf[start..end], self.win.base)
        {
            // The payload: the msg_id before the row's data.
            self.last = Some((
                row.offset,
                b'D',
                start + row.data.start - 2..start + row.data.end,
            ));
            return Ok(Some(Next::Row {
                offset: row.offset,
                data: start + row.data.start..start + row.data.end,
                sub: row.sub,
                timestamp: row.timestamp,
            }));
        }
        loop {
            let window = self.win.bytes();
            let step = self.walker.step(window, self.win.base, self.win.eof)?;
            match step {
                Step::End => return Ok(None),
                Step::NeedMore { keep_from } => {
                    self.win.fill(keep_from)?;
                }
                Step::Applied {
                    offset,
                    applied,
                    payload,
                } => {
                    // A message applied with a note is the message's event, then the
                    // note's: a tool that copies messages copies it.
                    let applied = match applied {
                        Applied::Noted(d) => {
                            self.pending = Some(Box::new(d));
                            Applied::Nothing
                        }
                        other => other,
                    };
                    // A diagnostic stands for no message (its offset may lie outside the
                    // window).
                    let (ty, range) = if let Applied::Diagnostic(_) = applied {
                        self.last = None;
                        (0, 0..0)
                    } else {
                        let at = self.win.start
                            + (offset - self.win.base) as usize
                            + super::MESSAGE_HEADER_LEN;
                        let range = at..at + payload.len();
                        self.last = Some((offset, self.win.buf[at - 1], range.clone()));
                        (self.win.buf[at - 1], range)
                    };
                    return Ok(Some(match applied {
                        // (A noted message is `Nothing` by now, its note pending.)
                        Applied::Nothing | Applied::Noted(_) => match MessageType::from_byte(ty) {
                            // A row of a subscription that cannot be decoded (said once,
                            // at the subscription): not a definition, and no row either.
                            Some(MessageType::Data) | None => continue,
                            Some(ty) => Next::Definition { offset, ty },
                        },
                        Applied::Subscribed {
                            diagnostic,
                            duplicate,
                            ..
                        } => {
                            let mut notes = diagnostic.map(Box::new).into_iter().chain(duplicate);
                            self.pending = notes.next();
                            self.pending_next = notes.next();
                            Next::Subscription
                        }
                        Applied::Row { sub, timestamp } => Next::Row {
                            offset,
                            data: range.start + 2..range.end,
                            sub,
                            timestamp,
                        },
                        Applied::Logged(m) => Next::Event(Event::Logged(m)),
                        Applied::Dropout(d) => Next::Event(Event::Dropout(d)),
                        Applied::ParameterChange(c) => Next::Event(Event::ParameterChange(c)),
                        Applied::Sync => Next::Event(Event::Sync { offset }),
                        Applied::Diagnostic(d) => Next::Diagnostic(Box::new(d)),
                    }));
                }
            }
        }
    }

    /// The event of what [`StreamReader::advance`] moved to.
    fn event(&self, next: Next) -> Event<'_> {
        match next {
            Next::Row {
                offset,
                data,
                sub,
                timestamp,
            } => Event::Row(Row {
                timestamp,
                offset,
                data: &self.win.buf[data],
                subscription: &self.walker.meta.subscriptions[sub],
                schema: &self.walker.meta.schema,
            }),
            Next::Definition { offset, ty } => Event::Definition { offset, ty },
            Next::Subscription => {
                Event::Subscription(self.walker.meta.subscriptions.last().expect("just added"))
            }
            Next::Diagnostic(d) => Event::Diagnostic(d),
            Next::Event(e) => e,
        }
    }
}
