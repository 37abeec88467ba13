//! Where the rows of a time series go: any [`SeriesSink`]. The analysis streams one row per
//! sample and keeps none, so a run of millions of steps needs no memory for them; files are
//! written by the sinks of [`crate::series_file`] (CSV, .npy), and [`SeriesCollector`] keeps a
//! short run in memory for library users.

/// A receiver of time-series rows: [`SeriesSink::begin`] once with the column names, then
/// [`SeriesSink::row`] per sample (values in the order of the columns, time increasing), then
/// [`SeriesSink::finish`] once.
pub trait SeriesSink {
    /// The column names, before any row.
    fn begin(&mut self, columns: &[&'static str]) -> std::io::Result<()>;
    /// One row: a value per column.
    fn row(&mut self, values: &[f64]) -> std::io::Result<()>;
    /// After the last row (flushes files, completes headers).
    fn finish(&mut self) -> std::io::Result<()>;
}

/// A sink that drops every row: the analysis still computes its events.
#[derive(Debug, Clone, Copy, Default)]
pub struct DiscardSink;

impl SeriesSink for DiscardSink {
    fn begin(&mut self, _: &[&'static str]) -> std::io::Result<()> {
        Ok(())
    }
    fn row(&mut self, _: &[f64]) -> std::io::Result<()> {
        Ok(())
    }
    fn finish(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// A sink that forwards every call to each of its sinks in turn (several `--series` files
/// from one run); the first error stops the call.
pub struct TeeSink(pub Vec<Box<dyn SeriesSink>>);

impl SeriesSink for TeeSink {
    fn begin(&mut self, columns: &[&'static str]) -> std::io::Result<()> {
        self.0.iter_mut().try_for_each(|s| s.begin(columns))
    }
    fn row(&mut self, values: &[f64]) -> std::io::Result<()> {
        self.0.iter_mut().try_for_each(|s| s.row(values))
    }
    fn finish(&mut self) -> std::io::Result<()> {
        self.0.iter_mut().try_for_each(|s| s.finish())
    }
}

/// A time series held in memory, column by column (for short runs: every row is kept).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SeriesCollector {
    /// Column names, in order.
    pub names: Vec<&'static str>,
    /// One vector per column, all of the same length.
    pub columns: Vec<Vec<f64>>,
}

impl SeriesCollector {
    /// The column `name`, if present.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names.iter().position(|n| *n == name).map(|i| self.columns[i].as_slice())
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// Whether no row was received.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl SeriesSink for SeriesCollector {
    fn begin(&mut self, columns: &[&'static str]) -> std::io::Result<()> {
        self.names = columns.to_vec();
        self.columns = vec![Vec::new(); columns.len()];
        Ok(())
    }
    fn row(&mut self, values: &[f64]) -> std::io::Result<()> {
        for (c, v) in self.columns.iter_mut().zip(values) {
            c.push(*v);
        }
        Ok(())
    }
    fn finish(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}
