//! A user's file, recognised by its content: QDYN's output files by their first line
//! ([`super::qdyn`]), a JSON report by its `cycle` object, a JSON trajectory by its columns,
//! and otherwise a CSV trajectory ([`super::input`]).

use super::input::UserReport;
use super::input::{check, read_csv, read_json_trajectory, InputError, Trajectory, UserCycle};
use super::qdyn::{QdynFile, QdynOutput};
use super::quantity::Quantity;

/// A user's file: a trajectory or a report.
#[derive(Debug, Clone, PartialEq)]
pub enum UserData {
    /// t, u, v, θ samples.
    Trajectory(Trajectory),
    /// QDYN's `output_ot_*` or a spring-block's `output_vmax`, in SI units
    /// ([`super::qdyn::to_trajectory`] turns it into the scene's variables).
    Qdyn(QdynOutput),
    /// The `cycle` object of a report.
    Report(UserCycle),
}

/// Reads a user's file (QDYN's output, CSV or JSON); errors say what is wrong and where (file
/// lines for CSV and QDYN's files, JSON paths for JSON), naming the column and the value.
pub fn read_user_data(text: &str) -> Result<UserData, InputError> {
    if QdynFile::recognise(text).is_some() {
        return super::qdyn::read_qdyn_output(text).map(UserData::Qdyn);
    }
    if text.trim_start().starts_with('{') {
        let json: serde_json::Value =
            serde_json::from_str(text).map_err(|e| InputError::Json(e.to_string()))?;
        if json.get("cycle").is_some() {
            let report: UserReport = serde_path_to_error::deserialize(&json).map_err(|e| {
                let path = e.path().to_string();
                InputError::ReportKey { path, message: e.into_inner().to_string() }
            })?;
            if Quantity::ALL.iter().all(|&q| report.cycle.get(q).is_none()) {
                return Err(InputError::NoComparedKey);
            }
            return Ok(UserData::Report(report.cycle));
        }
        return read_json_trajectory(&json).and_then(check).map(UserData::Trajectory);
    }
    read_csv(text).and_then(check).map(UserData::Trajectory)
}
