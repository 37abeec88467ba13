//! A laboratory friction record: time, friction and (optionally) load-point displacement,
//! read from a delimited text file whose columns are chosen by their header names.

use std::path::Path;

/// Which header names hold time, friction and the load-point displacement.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColumnNames {
    /// The time column (s).
    pub t: String,
    /// The friction column.
    pub mu: String,
    /// The load-point displacement column (µm), if the record has one.
    pub x_lp: Option<String>,
}

impl Default for ColumnNames {
    /// `t`, `mu` and `x_lp`.
    fn default() -> Self {
        Self { t: "t".into(), mu: "mu".into(), x_lp: Some("x_lp".into()) }
    }
}

impl ColumnNames {
    /// Parses `t=Time(s),x_lp=Displ(microns),mu=Friction`: each of `t`, `mu` and `x_lp` mapped
    /// to a header name; those not given keep their default name (`x_lp` is then optional).
    pub fn parse(spec: &str) -> Result<Self, String> {
        let mut names = Self::default();
        for item in spec.split(',').filter(|s| !s.trim().is_empty()) {
            let Some((key, name)) = item.split_once('=') else {
                return Err(format!("--columns: \"{item}\" is not KEY=NAME (e.g. t=Time(s),mu=Friction,x_lp=Displ(microns))"));
            };
            let name = name.trim().to_string();
            match key.trim() {
                "t" => names.t = name,
                "mu" => names.mu = name,
                "x_lp" => names.x_lp = Some(name),
                other => {
                    return Err(format!(
                        "--columns: unknown key \"{other}\"; the keys are t, mu and x_lp"
                    ))
                }
            }
        }
        Ok(names)
    }
}

/// A friction record: strictly increasing times with friction, and the load-point
/// displacement where the record has it.
#[derive(Debug, Clone, PartialEq)]
pub struct FrictionRecord {
    /// Times (s), strictly increasing.
    pub t: Vec<f64>,
    /// Friction.
    pub mu: Vec<f64>,
    /// Load-point displacement (µm), if read.
    pub x_lp: Option<Vec<f64>>,
}

/// Most samples a record may hold: a lab record has thousands; millions is a wrong file.
pub const MAX_SAMPLES: usize = 2_000_000;

impl FrictionRecord {
    /// Reads `path`: one header line of column names, then rows of numbers, separated by tabs,
    /// commas or blanks (the header's separator decides). The column named `names.x_lp` is
    /// read if present; it is required only when `names.x_lp` was given explicitly and
    /// `require_x_lp` is set.
    pub fn read(path: &Path, names: &ColumnNames, require_x_lp: bool) -> Result<Self, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        Self::parse(&text, &path.display().to_string(), names, require_x_lp)
    }

    /// [`FrictionRecord::read`] on text; `source` names it in errors.
    pub fn parse(
        text: &str,
        source: &str,
        names: &ColumnNames,
        require_x_lp: bool,
    ) -> Result<Self, String> {
        let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
        let Some((_, header)) = lines.next() else {
            return Err(format!("{source}: the file is empty; it needs a header line of column names and rows of numbers"));
        };
        let split = separator(header);
        let columns: Vec<&str> = split(header);
        let index = |name: &str| columns.iter().position(|c| *c == name);
        let missing = |key: &str, name: &str| {
            format!(
                "{source}: no column \"{name}\" for {key}; the columns are {}; choose with --columns {key}=NAME",
                columns.iter().map(|c| format!("\"{c}\"")).collect::<Vec<_>>().join(", ")
            )
        };
        let it = index(&names.t).ok_or_else(|| missing("t", &names.t))?;
        let imu = index(&names.mu).ok_or_else(|| missing("mu", &names.mu))?;
        let ix = match &names.x_lp {
            Some(name) => match index(name) {
                Some(i) => Some(i),
                None if require_x_lp => return Err(missing("x_lp", name)),
                None => None,
            },
            None => None,
        };
        let mut record = Self { t: vec![], mu: vec![], x_lp: ix.map(|_| vec![]) };
        for (number, line) in lines {
            let fields = split(line);
            let value = |i: usize, key: &str| -> Result<f64, String> {
                let field = fields.get(i).ok_or_else(|| {
                    format!(
                        "{source}:{}: the row has {} fields; {key} is column {}",
                        number + 1,
                        fields.len(),
                        i + 1
                    )
                })?;
                match field.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(format!(
                        "{source}:{}: {key} = \"{field}\" is not a finite number",
                        number + 1
                    )),
                }
            };
            let t = value(it, "t")?;
            if let Some(&last) = record.t.last() {
                if t <= last {
                    return Err(format!("{source}:{}: time {t} is not after the previous {last}; times must increase strictly", number + 1));
                }
            }
            record.t.push(t);
            record.mu.push(value(imu, "mu")?);
            if let (Some(i), Some(x)) = (ix, record.x_lp.as_mut()) {
                x.push(value(i, "x_lp")?);
            }
            if record.t.len() > MAX_SAMPLES {
                return Err(format!(
                    "{source}: more than {MAX_SAMPLES} samples; is this the right file?"
                ));
            }
        }
        if record.t.len() < 2 {
            return Err(format!("{source}: {} data rows; a fit needs many more", record.t.len()));
        }
        Ok(record)
    }
}

/// The field splitter for a header: tab if it has one, else comma, else runs of blanks.
fn separator(header: &str) -> fn(&str) -> Vec<&str> {
    if header.contains('\t') {
        |l| l.split('\t').map(str::trim).collect()
    } else if header.contains(',') {
        |l| l.split(',').map(str::trim).collect()
    } else {
        |l| l.split_whitespace().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_columns_by_name_and_names_what_is_wrong() {
        let names = ColumnNames::parse("t=Time(s),x_lp=Displ(microns),mu=Friction").unwrap();
        let text =
            "Time(s)\tDispl(microns)\tFriction\n1.0\t10\t0.6\n1.1\t10.5\t0.61\n1.2\t11\t0.62\n";
        let r = FrictionRecord::parse(text, "f", &names, true).unwrap();
        assert_eq!(r.t, vec![1.0, 1.1, 1.2]);
        assert_eq!(r.x_lp.unwrap(), vec![10.0, 10.5, 11.0]);
        let e = FrictionRecord::parse(text, "f", &ColumnNames::default(), false).unwrap_err();
        assert!(e.contains("no column \"t\"") && e.contains("\"Time(s)\""), "{e}");
        let bad = "t,mu\n1,0.6\n1,0.7\n";
        let e = FrictionRecord::parse(bad, "f", &ColumnNames::default(), false).unwrap_err();
        assert!(e.contains("f:3") && e.contains("increase"), "{e}");
        assert!(ColumnNames::parse("time=T").unwrap_err().contains("unknown key"));
    }
}
