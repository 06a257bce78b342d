//! How the stages' loops are split over rayon's threads: the smallest piece
//! of work worth handing to the pool.
//!
//! A parallel loop called from outside the pool (the solver's own thread)
//! hands its pieces to rayon's workers and waits for them: some tens of
//! microseconds on this project's machines, more than a whole loop of a
//! small scene (the paper's case has 896 points and 24 active nodes). A
//! loop given no more than one piece of the sizes below runs on the calling
//! thread, with no handoff (`with_min_len` on rayon's iterators: it splits
//! no piece below that length).

/// Points a piece when each asks its material for a response (a stress, or
/// a stress and tangent: 0.1 to 0.3 us each).
pub const POINT_RESPONSES: usize = 256;

/// Items a piece of bookkeeping (a node's or point's indices, a copy or a
/// sum of a few numbers: some nanoseconds each).
pub const BOOKKEEPING: usize = 4096;
