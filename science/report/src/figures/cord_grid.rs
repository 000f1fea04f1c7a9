//! The cords' panels as the experiment's table when the data have one: every capstan diameter
//! with every wrap, one cord each (the thesis: 2 diameters × 5 wraps). On a page, one row per
//! diameter and one column per wrap; in a column too narrow for a panel per wrap, one column
//! per diameter and one row per wrap. Otherwise (or where neither fits) `None`, and the
//! figure keeps its reflowed grid.

use super::panels_that_fit;
use crate::plot::{Entry, Layout};
use capstan_engine::analysis::Analysis;
use capstan_engine::fit::stats::distinct;

/// The narrowest panel of a cord table, px: a cord's title ("630°, D = 12.7 mm") and tick
/// labels still clear of each other (narrower than the reflowed grid's
/// [`crate::plot::MIN_PANEL_W`]: in a table the panels' positions say what they are).
pub const MIN_TABLE_PANEL_W: u32 = 120;

/// The cords laid out as a table: the grid (columns, cell width and height, px), the cords in
/// panel order (row by row), and the caption's sentence saying what the rows and columns are.
pub struct CordTable {
    /// Columns, and each cell's width and height, px.
    pub grid: (usize, u32, u32),
    /// The cords in panel order, row by row.
    pub cords: Vec<usize>,
    /// The caption's sentence: what the rows and the columns are.
    pub note: &'static str,
}

/// The cords of `a` as a diameter × wrap table for panels of natural size `w`×`h` px, if the
/// data have that structure and every panel fits `layout`'s width and page.
pub fn cord_table(
    a: &Analysis,
    layout: &Layout,
    (w, h): (u32, u32),
    titles: &[&str],
    x_label: &str,
    legend: &[Entry],
) -> Option<CordTable> {
    let groups = &a.obs.groups;
    let diameters = distinct(groups.iter().map(|g| g.diameter_mm));
    let wraps = distinct(groups.iter().map(|g| g.wrap_deg));
    if diameters.len() < 2 || wraps.len() < 2 || diameters.len() * wraps.len() != groups.len() {
        return None;
    }
    // The cord at (diameter i, wrap j), each pair exactly once.
    let mut at = vec![None; groups.len()];
    for (g, grp) in groups.iter().enumerate() {
        let i = diameters
            .iter()
            .position(|d| d.to_bits() == grp.diameter_mm.to_bits())?;
        let j = wraps
            .iter()
            .position(|x| x.to_bits() == grp.wrap_deg.to_bits())?;
        let slot = &mut at[i * wraps.len() + j];
        if slot.replace(g).is_some() {
            return None;
        }
    }
    let at: Vec<usize> = at.into_iter().collect::<Option<_>>()?;
    let (nd, nw) = (diameters.len(), wraps.len());
    // Rows of diameters on a page; else rows of wraps (columns of diameters).
    [true, false].into_iter().find_map(|diameter_rows| {
        let (cols, rows) = if diameter_rows { (nw, nd) } else { (nd, nw) };
        let grid = layout.grid_exact(cols, w, h, MIN_TABLE_PANEL_W)?;
        if panels_that_fit(layout, grid, titles, x_label, legend) < groups.len() {
            return None;
        }
        let cell = |r: usize, c: usize| if diameter_rows { (r, c) } else { (c, r) };
        let cords = (0..rows)
            .flat_map(|r| (0..cols).map(move |c| cell(r, c)))
            .map(|(i, j)| at[i * nw + j])
            .collect();
        Some(CordTable {
            grid,
            cords,
            note: if diameter_rows {
                " One row per capstan diameter, one column per wrap."
            } else {
                " One column per capstan diameter, one row per wrap."
            },
        })
    })
}
