//! Time-series files: the [`SeriesSink`]s behind `stickslip run SCENE --series FILE`.
//!
//! - **CSV** (FILE ends in `.csv`): a header line with the column names, then one line per
//!   row, every value in Rust's shortest round-trip form (`{:e}`: no digit lost).
//! - **NumPy .npy** (any other suffix): a one-dimensional *structured* array with one
//!   little-endian float64 field per column, which `np.load(FILE)` reads in one call
//!   (`a["t"]`, `a["v"]`, …) and `pandas.DataFrame(np.load(FILE))` turns into a table. Written
//!   with the `npyz` crate: it streams rows of a length unknown in advance (`begin_1d` writes
//!   the header with room for the count and rewrites the count on `finish`, which needs only
//!   `Seek`), its only heavy dependency is the header parser (pest), and it reads the format
//!   back, which the tests use. Arrow IPC or Parquet would serve pandas as well but pull in
//!   far larger dependency trees (compile time on a 2-core machine), and .npy needs no
//!   library but numpy on the reader's side.
//!
//! Both stream: a row is written (buffered) as it comes and nothing is kept.

pub mod qdyn;

use crate::analysis::time_series::SeriesSink;
use npyz::{DType, Field, TypeRead, TypeWrite, WriterBuilder};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// CSV rows to any writer.
pub struct CsvSink<W: Write> {
    out: W,
}

impl<W: Write> CsvSink<W> {
    /// Rows to `out`.
    pub fn new(out: W) -> Self {
        Self { out }
    }
}

impl<W: Write> SeriesSink for CsvSink<W> {
    fn begin(&mut self, columns: &[&'static str]) -> io::Result<()> {
        writeln!(self.out, "{}", columns.join(","))
    }

    fn row(&mut self, values: &[f64]) -> io::Result<()> {
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.out.write_all(b",")?;
            }
            write!(self.out, "{v:e}")?;
        }
        self.out.write_all(b"\n")
    }

    fn finish(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

/// One row of float64 values, as one record of the structured array.
struct Row(Vec<f64>);

/// Writes a [`Row`] field by field with float64 writers.
struct RowWriter(Vec<<f64 as npyz::Serialize>::TypeWriter>);

impl TypeWrite for RowWriter {
    type Value = Row;

    fn write_one<W: Write>(&self, mut w: W, row: &Row) -> io::Result<()> {
        for (writer, v) in self.0.iter().zip(&row.0) {
            writer.write_one(&mut w, v)?;
        }
        Ok(())
    }
}

impl npyz::Serialize for Row {
    type TypeWriter = RowWriter;

    fn writer(dtype: &DType) -> Result<RowWriter, npyz::DTypeError> {
        let fields = match dtype {
            DType::Record(fields) => fields.iter().map(|f| &f.dtype).collect(),
            plain => vec![plain],
        };
        fields
            .into_iter()
            .map(<f64 as npyz::Serialize>::writer)
            .collect::<Result<_, _>>()
            .map(RowWriter)
    }
}

/// Reads a [`Row`] field by field with float64 readers.
struct RowReader(Vec<<f64 as npyz::Deserialize>::TypeReader>);

impl TypeRead for RowReader {
    type Value = Row;

    fn read_one<R: io::Read>(&self, mut r: R) -> io::Result<Row> {
        self.0.iter().map(|reader| reader.read_one(&mut r)).collect::<io::Result<_>>().map(Row)
    }
}

impl npyz::Deserialize for Row {
    type TypeReader = RowReader;

    fn reader(dtype: &DType) -> Result<RowReader, npyz::DTypeError> {
        let fields = match dtype {
            DType::Record(fields) => fields.iter().map(|f| &f.dtype).collect(),
            plain => vec![plain],
        };
        fields
            .into_iter()
            .map(<f64 as npyz::Deserialize>::reader)
            .collect::<Result<_, _>>()
            .map(RowReader)
    }
}

/// Rows of a structured .npy array, streamed to a file; the row count is written into the
/// header on [`SeriesSink::finish`].
pub struct NpySink {
    file: Option<BufWriter<File>>,
    writer: Option<npyz::NpyWriter<Row, BufWriter<File>>>,
    row: Row,
}

impl NpySink {
    /// Rows to the file `file` (created or truncated by the caller).
    pub fn new(file: File) -> Self {
        Self { file: Some(BufWriter::new(file)), writer: None, row: Row(Vec::new()) }
    }
}

fn not_begun() -> io::Error {
    io::Error::other("a row before the series began (SeriesSink::begin)")
}

impl SeriesSink for NpySink {
    fn begin(&mut self, columns: &[&'static str]) -> io::Result<()> {
        let file = self.file.take().ok_or_else(|| io::Error::other("the series began twice"))?;
        let f8: npyz::TypeStr = "<f8".parse().map_err(io::Error::other)?;
        let dtype = DType::Record(
            columns
                .iter()
                .map(|name| Field { name: name.to_string(), dtype: DType::Plain(f8.clone()) })
                .collect(),
        );
        self.writer = Some(npyz::WriteOptions::<Row>::new().dtype(dtype).writer(file).begin_1d()?);
        Ok(())
    }

    fn row(&mut self, values: &[f64]) -> io::Result<()> {
        self.row.0.clear();
        self.row.0.extend_from_slice(values);
        self.writer.as_mut().ok_or_else(not_begun)?.push(&self.row)
    }

    fn finish(&mut self) -> io::Result<()> {
        self.writer.take().ok_or_else(not_begun)?.finish()
    }
}

/// The sink for `path`: CSV when it ends in `.csv` (any case), .npy otherwise. The file is
/// created (or truncated) now, so that a path that cannot be written fails before the run.
pub fn create(path: &Path) -> io::Result<Box<dyn SeriesSink>> {
    create_as(path, path)
}

/// [`create`] writing to `file` in the format that `path` names (`file` being, e.g., a
/// temporary file to be renamed to `path` when the series is complete).
pub fn create_as(file: &Path, path: &Path) -> io::Result<Box<dyn SeriesSink>> {
    let file = File::create(file)?;
    if is_csv(path) {
        Ok(Box::new(CsvSink::new(BufWriter::new(file))))
    } else {
        Ok(Box::new(NpySink::new(file)))
    }
}

/// Whether `path` names a CSV file (suffix `.csv`, any case).
pub fn is_csv(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"))
}

/// A series read back from a file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadSeries {
    /// Column names, in order.
    pub names: Vec<String>,
    /// One vector per column.
    pub columns: Vec<Vec<f64>>,
}

impl ReadSeries {
    /// The column `name`, if present.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names.iter().position(|n| n == name).map(|i| self.columns[i].as_slice())
    }
}

/// Reads a structured float64 .npy array as written by [`NpySink`] (or by numpy for a
/// structured array of float64 fields).
pub fn read_npy(path: &Path) -> io::Result<ReadSeries> {
    let npy = npyz::NpyFile::new(io::BufReader::new(File::open(path)?))?;
    let names: Vec<String> = match npy.dtype() {
        DType::Record(fields) => fields.into_iter().map(|f| f.name).collect(),
        other => {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!("{}: not a structured array (dtype {})", path.display(), other.descr()),
            ))
        }
    };
    let rows: Vec<Row> = npy.into_vec()?;
    let mut columns = vec![Vec::with_capacity(rows.len()); names.len()];
    for row in rows {
        for (c, v) in columns.iter_mut().zip(row.0) {
            c.push(v);
        }
    }
    Ok(ReadSeries { names, columns })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_rows_stream_and_read_back_exactly() {
        let dir = std::env::temp_dir().join(format!("stickslip-npy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("s.npy");
        let mut sink = create(&path).unwrap();
        sink.begin(&["t", "v"]).unwrap();
        let rows = [[0.0, 1e-300], [1.0 / 3.0, 7.5e9], [1e3 + 1e-13, f64::MIN_POSITIVE]];
        for r in &rows {
            sink.row(r).unwrap();
        }
        sink.finish().unwrap();
        let back = read_npy(&path).unwrap();
        assert_eq!(back.names, ["t", "v"]);
        assert_eq!(back.column("t").unwrap(), [rows[0][0], rows[1][0], rows[2][0]]);
        assert_eq!(back.column("v").unwrap(), [rows[0][1], rows[1][1], rows[2][1]]);
        let bytes = std::fs::read(&path).unwrap();
        let header = String::from_utf8_lossy(&bytes[..128]);
        assert!(header.contains("'shape': (3,)"), "{header}");
        assert!(header.contains("('t', '<f8')"), "{header}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn csv_rows_round_trip_every_digit() {
        let mut out = Vec::new();
        let mut sink = CsvSink::new(&mut out);
        sink.begin(&["t", "v"]).unwrap();
        sink.row(&[1.0 / 3.0, 1e-300]).unwrap();
        sink.finish().unwrap();
        let text = String::from_utf8(out).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("t,v"));
        let cells: Vec<f64> =
            lines.next().unwrap().split(',').map(|c| c.parse().unwrap()).collect();
        assert_eq!(cells, [1.0 / 3.0, 1e-300]);
    }
}
