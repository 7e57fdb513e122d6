//! PSD (stub)
