//! The leave-one-out objective of the paper (Eq. 4) for calibrating h.
