//! The `shadows` study (stub: see the issue that owns it).

use crate::record::Column;

/// CSV columns this study owns (documented in results/README.md).
pub const COLUMNS: &[Column] = &[];
