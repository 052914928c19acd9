//! What the data-row pass reads against and fills: the [`Schema`] (the
//! columns' fields, factors and signs, the delimiter) and the [`Rows`] of
//! values and their line numbers. The fast path (`fast`) and the
//! field-by-field path (`rows`) both work on them.

use super::dialect::Delimiter;
use crate::error::ParseError;
use a3d_model::Quantity;
use std::path::Path;

/// What the data-row pass needs to know about the table.
pub(super) struct Schema<'a> {
    pub(super) path: &'a Path,
    pub(super) delim: Delimiter,
    pub(super) decimal_comma: bool,
    /// Column of x, y, z.
    pub(super) coords: [Option<usize>; 3],
    pub(super) node: Option<usize>,
    pub(super) region: Option<usize>,
    pub(super) value_cols: &'a [(usize, Quantity)],
    /// Unit factor × sign per column.
    pub(super) factors: &'a [f64],
}

impl Schema<'_> {
    /// The columns whose missing fields are tracked: the values, then node, then region.
    pub(super) fn tracked(&self) -> Vec<Option<usize>> {
        let mut out: Vec<Option<usize>> = self.value_cols.iter().map(|(c, _)| Some(*c)).collect();
        out.push(self.node);
        out.push(self.region);
        out
    }
}

/// Data rows read from one chunk (or from the whole body once merged).
#[derive(Default)]
pub(super) struct Rows {
    pub(super) positions: Vec<[f64; 3]>,
    /// The id column's value, when the row has one.
    pub(super) ids: Vec<Option<i64>>,
    /// One vector per value column with a value (NaN when absent) for every row.
    pub(super) values: Vec<Vec<f64>>,
    pub(super) regions: Vec<String>,
    /// 1-based line of each row.
    pub(super) lines: Vec<usize>,
    /// Per tracked column ([`Schema::tracked`]): some row has a value.
    pub(super) has_value: Vec<bool>,
    /// Per tracked column: the first row that lacks the field, as (line,
    /// column past its end, fields in the row).
    pub(super) first_short: Vec<Option<(usize, usize, usize)>>,
    /// The first row whose id cell is present but empty, as (line, column).
    pub(super) first_empty_id: Option<(usize, usize)>,
    pub(super) errors: Vec<ParseError>,
}

impl Rows {
    /// Empty rows with room for `capacity` rows (a chunk's line count: its
    /// columns are then allocated once, not grown by doubling).
    pub(super) fn new(schema: &Schema<'_>, capacity: usize) -> Rows {
        let n_tracked = schema.value_cols.len() + 2;
        Rows {
            positions: Vec::with_capacity(capacity),
            ids: Vec::with_capacity(capacity),
            values: (0..schema.value_cols.len())
                .map(|_| Vec::with_capacity(capacity))
                .collect(),
            lines: Vec::with_capacity(capacity),
            has_value: vec![false; n_tracked],
            first_short: vec![None; n_tracked],
            ..Rows::default()
        }
    }

    pub(super) fn short(&mut self, t: usize, line: usize, col: usize, n_fields: usize) {
        if self.first_short[t].is_none() {
            self.first_short[t] = Some((line, col, n_fields));
        }
    }
}
