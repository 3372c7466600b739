//! The one table layout of terminal output: `render`'s summary, `bench`'s and `sweep`'s tables
//! ([`crate::bench::report::terminal_table`], [`crate::sweep::report::terminal_tables`]) and
//! `explain`'s step-by-step table are each a [`Table`] (headings, rows of cells, each column as
//! wide as its widest cell), laid out as aligned text or as a Markdown table, so that no report
//! lays out columns by hand.

/// A column of a table of `Row`s: its heading, and the cell it shows of a row.
pub type Column<Row> = (&'static str, fn(&Row) -> String);

/// A table: headings, rows of cells, and how its columns align.
#[derive(Debug, Clone)]
pub struct Table {
    /// One heading a column.
    headings: Vec<String>,
    /// The first `left` columns (names) align left, the rest (numbers) right.
    left: usize,
    /// The least width of each column (none: as wide as its widest cell).
    least_widths: Vec<usize>,
    /// The rows, one cell a column.
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with `headings` and no rows, its first `left` columns aligned left.
    pub fn new(headings: Vec<String>, left: usize) -> Self {
        Self {
            headings,
            left,
            least_widths: Vec::new(),
            rows: Vec::new(),
        }
    }

    /// The table of `rows`, one column per `(heading, cell)`.
    pub fn of<Row>(columns: &[Column<Row>], rows: &[Row], left: usize) -> Self {
        let mut table = Self::new(
            columns
                .iter()
                .map(|(heading, _)| (*heading).into())
                .collect(),
            left,
        );
        for row in rows {
            table.push(columns.iter().map(|(_, cell)| cell(row)).collect());
        }
        table
    }

    /// With column `c` at least `least_widths[c]` wide, so that short runs line up with long.
    pub fn at_least(mut self, least_widths: Vec<usize>) -> Self {
        self.least_widths = least_widths;
        self
    }

    /// Adds a row, one cell a column.
    pub fn push(&mut self, cells: Vec<String>) {
        debug_assert_eq!(cells.len(), self.headings.len(), "one cell a column");
        self.rows.push(cells);
    }

    /// Whether the table has no row.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Each column's width: its widest cell or heading, at least its least width.
    fn widths(&self) -> Vec<usize> {
        (0..self.headings.len())
            .map(|c| {
                self.rows
                    .iter()
                    .chain([&self.headings])
                    .map(|row| row[c].chars().count())
                    .fold(self.least_widths.get(c).copied().unwrap_or(0), usize::max)
            })
            .collect()
    }

    /// The cells of `row` padded to `widths`, aligned as the columns are.
    fn padded(&self, row: &[String], widths: &[usize]) -> Vec<String> {
        row.iter()
            .zip(widths)
            .enumerate()
            .map(|(c, (cell, &width))| {
                if c < self.left {
                    format!("{cell:<width$}")
                } else {
                    format!("{cell:>width$}")
                }
            })
            .collect()
    }

    /// As text: the line of headings, then a line a row, `gap` spaces between columns, no
    /// trailing spaces.
    pub fn text(&self, gap: usize) -> String {
        let widths = self.widths();
        let separator = " ".repeat(gap);
        let mut text = String::new();
        for row in [&self.headings].into_iter().chain(&self.rows) {
            text.push_str(self.padded(row, &widths).join(&separator).trim_end());
            text.push('\n');
        }
        text
    }

    /// As a Markdown table, padded so that it lines up as text too: the headings, the rule, a
    /// line a row.
    pub fn markdown(&self) -> String {
        let widths = self.widths();
        let line = |cells: Vec<String>| format!("| {} |\n", cells.join(" | "));
        let rule: Vec<String> = widths.iter().map(|&w| "-".repeat(w)).collect();
        let mut text = line(self.padded(&self.headings, &widths));
        text.push_str(&format!("|-{}-|\n", rule.join("-|-")));
        for row in &self.rows {
            text.push_str(&line(self.padded(row, &widths)));
        }
        text
    }
}

#[cfg(test)]
mod tests {
    use super::{Column, Table};

    #[test]
    fn a_table_pads_names_left_and_numbers_right() {
        type Row = (&'static str, u32);
        let columns: [Column<Row>; 2] = [
            ("scheme", |r| r.0.to_string()),
            ("lost", |r| r.1.to_string()),
        ];
        let table = Table::of(&columns, &[("mdts", 0), ("kbuffer-stores", 1234)], 1);
        let text = table.text(2);
        assert_eq!(
            text, "scheme          lost\nmdts               0\nkbuffer-stores  1234\n",
            "{text}"
        );
        let wide = table.at_least(vec![0, 6]).text(1);
        assert_eq!(
            wide, "scheme           lost\nmdts                0\nkbuffer-stores   1234\n",
            "{wide}"
        );
    }

    #[test]
    fn a_markdown_table_has_a_rule_under_its_headings() {
        let mut table = Table::new(vec!["step".into(), "memory after".into()], 2);
        table.push(vec!["0".into(), "[1, 2]".into()]);
        let text = table.markdown();
        assert_eq!(
            text, "| step | memory after |\n|------|--------------|\n| 0    | [1, 2]       |\n",
            "{text}"
        );
    }
}
