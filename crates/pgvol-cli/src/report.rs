//! The one shape of every `--json` report: the command's outputs, `warnings` (every warning the
//! run gave, printed or not, empty when none) and `seconds` (stage times and their `total`).
//! Warnings are collected here as they are given, so a report made in JSON mode, where nothing
//! goes to standard error, still carries them.

use std::sync::Mutex;
use std::time::Instant;

use anyhow::Result;
use serde::Serialize;

use crate::output::outln;

/// The warnings given so far in this run.
static WARNINGS: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Keeps `message` for the report.
pub fn record(message: &str) {
    if let Ok(mut list) = WARNINGS.lock() {
        list.push(message.to_string());
    }
}

/// Keeps `message` for the report and prints it on standard error unless `quiet`.
pub fn warn(quiet: bool, message: &str) {
    record(message);
    if !quiet {
        eprintln!("warning: {message}");
    }
}

/// The warnings kept so far, in order.
fn warnings() -> Vec<String> {
    WARNINGS.lock().map(|list| list.clone()).unwrap_or_default()
}

/// Stage times of a run, from its start.
pub struct Seconds {
    start: Instant,
    stages: Vec<(String, f64)>,
}

impl Seconds {
    /// No stages yet; the total counts from `start`.
    pub fn since(start: Instant) -> Self {
        Self {
            start,
            stages: Vec::new(),
        }
    }

    /// The same with stage `name` taking `seconds`.
    pub fn stage(mut self, name: &str, seconds: f64) -> Self {
        self.stages.push((name.to_string(), seconds));
        self
    }

    /// The same with each of `stages`.
    pub fn stages<'a>(self, stages: impl IntoIterator<Item = (&'a str, f64)>) -> Self {
        stages
            .into_iter()
            .fold(self, |s, (name, seconds)| s.stage(name, seconds))
    }

    fn json(&self) -> serde_json::Value {
        let mut map = serde_json::Map::new();
        for (name, s) in &self.stages {
            map.insert(name.clone(), (*s).into());
        }
        map.insert("total".into(), self.start.elapsed().as_secs_f64().into());
        serde_json::Value::Object(map)
    }
}

/// The report of `outputs` (a struct or JSON object of the command's results) with the run's
/// `warnings` and `seconds` added.
pub fn json(outputs: &impl Serialize, seconds: &Seconds) -> Result<serde_json::Value> {
    let mut report = match serde_json::to_value(outputs)? {
        serde_json::Value::Object(map) => map,
        other => anyhow::bail!("a report's outputs must be a JSON object, not {other}"),
    };
    report.insert("warnings".into(), warnings().into());
    report.insert("seconds".into(), seconds.json());
    Ok(serde_json::Value::Object(report))
}

/// Prints the report (see [`json`]) as pretty JSON on standard output.
pub fn print(outputs: &impl Serialize, seconds: &Seconds) -> Result<()> {
    outln!(
        "{}",
        serde_json::to_string_pretty(&json(outputs, seconds)?)?
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_report_has_outputs_warnings_and_seconds() {
        let seconds = Seconds::since(Instant::now()).stage("fit", 0.5);
        let report = json(&serde_json::json!({ "output": "a.pgv" }), &seconds).unwrap();
        assert_eq!(report["output"], "a.pgv");
        assert!(report["warnings"].is_array());
        assert_eq!(report["seconds"]["fit"], 0.5);
        assert!(report["seconds"]["total"].as_f64().unwrap() >= 0.0);
        record("removed 2 pieces");
        let report = json(&serde_json::json!({}), &seconds).unwrap();
        assert!(report["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w == "removed 2 pieces"));
        assert!(json(&[1, 2], &seconds).is_err());
    }
}
