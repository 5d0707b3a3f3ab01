//! The line's tables: one row per point (line.csv), per point and diverter
//! (line_diverters.csv), and the parcel log, one row per parcel with its inputs, arrival,
//! destination and outcome (line_parcels.parquet). Columns carry their unit in the name
//! (SI; the angle in radians); diverters are numbered from 1 down the belt. The parcel log
//! is read from the run's compact log a batch at a time: writing it holds one batch of
//! parcels whole, not the stream.

use crate::contract::Error;
use crate::output::csv_bytes;
use arrow_array::builder::{Float64Builder, StringBuilder, UInt32Builder};
use arrow_array::{ArrayRef, Float64Array, RecordBatch, UInt32Array, UInt64Array};
use arrow_schema::{DataType, Field, Schema};
use divertsim_core::analysis::line::log::ParcelLog;
use divertsim_core::analysis::line::tally::LineTally;
use divertsim_core::analysis::line::{Collision, Line, LineOutcome, LineParcel};
use divertsim_core::analysis::population::reliability::CONFIDENCE;
use parquet::arrow::ArrowWriter;
use std::sync::Arc;

/// One point of a run, as the tables see it.
pub struct TableRow<'a> {
    /// The swept value ("" without a sweep).
    pub value: &'a str,
    pub line: &'a Line,
    pub tally: &'a LineTally,
    /// Every parcel (the parcel log, read back in batches of `PARCEL_BATCH` rows).
    pub log: &'a ParcelLog,
}

/// Rows of the parcel log per batch written (the file's layout depends on it: keep it).
const PARCEL_BATCH: usize = 100_000;

use super::cells::num;

/// One row per point: rates of every outcome with their intervals, throughput, arrivals.
pub fn points_csv(rows: &[TableRow]) -> Result<Vec<u8>, Error> {
    let mut header: Vec<String> = [
        "point",
        "parcels",
        "time_s",
        "arrival_rate_per_h",
        "throughput_per_h",
    ]
    .map(String::from)
    .to_vec();
    for k in LineOutcome::KINDS
        .iter()
        .chain(&["missorted", "struck", "overloaded"])
    {
        for part in ["count", "rate", "lower", "upper"] {
            header.push(format!("{k}_{part}"));
        }
    }
    let body = rows
        .iter()
        .map(|res| {
            let t = res.tally;
            let mut row = vec![
                res.value.to_string(),
                t.parcels.to_string(),
                num(t.time),
                num(t.arrival_rate()),
                num(t.line_throughput()),
            ];
            let mut props: Vec<_> = LineOutcome::KINDS
                .iter()
                .map(|k| t.rate(k, CONFIDENCE))
                .collect();
            props.push(t.missort_rate(CONFIDENCE));
            props.push(t.struck_rate(CONFIDENCE));
            props.push(t.overload_rate(CONFIDENCE));
            for p in props {
                row.extend([
                    p.successes.to_string(),
                    num(p.estimate),
                    num(p.lower),
                    num(p.upper),
                ]);
            }
            row
        })
        .collect::<Vec<_>>();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    csv_bytes(&header, &body).map_err(Error::io)
}

/// One row per point and diverter.
pub fn diverters_csv(rows: &[TableRow]) -> Result<Vec<u8>, Error> {
    let header = [
        "point",
        "diverter",
        "position_m",
        "share",
        "bound",
        "diverted",
        "arm_busy",
        "not_diverted",
        "wrongly_diverted_here",
        "divert_rate",
        "divert_rate_lower",
        "divert_rate_upper",
        "throughput_per_h",
        "paper_capacity_per_h",
        "cycles",
        "utilisation",
    ];
    let mut body = Vec::new();
    for res in rows {
        let (t, line) = (res.tally, res.line);
        for (d, div) in line.diverters.iter().enumerate() {
            let c = &t.diverters[d];
            let p = t.divert_rate(d, CONFIDENCE);
            body.push(vec![
                res.value.to_string(),
                (d + 1).to_string(),
                num(div.position),
                num(div.share),
                c.bound.to_string(),
                c.diverted.to_string(),
                c.busy.to_string(),
                c.not_diverted.to_string(),
                c.wrongly_diverted.to_string(),
                num(p.estimate),
                num(p.lower),
                num(p.upper),
                num(t.throughput(d)),
                num(div.paper_capacity()),
                c.cycles.to_string(),
                num(t.utilisation(line, d)),
            ]);
        }
    }
    csv_bytes(&header, &body).map_err(Error::io)
}

/// A float column of the parcel log.
type FloatOf = fn(&LineParcel) -> f64;

/// The parcel log of every point as the bytes of a Parquet file.
pub fn parcels_parquet(rows: &[TableRow]) -> Result<Vec<u8>, Error> {
    let floats: [(&str, FloatOf); 10] = [
        ("arrival_s", |p| p.arrival),
        ("headway_s", |p| p.headway),
        ("length_m", |p| p.length),
        ("width_m", |p| p.width),
        ("height_m", |p| p.height),
        ("mass_kg", |p| p.mass),
        ("offset_m", |p| p.offset),
        ("angle_rad", |p| p.angle),
        ("overload_ratio", |p| p.overload_ratio),
        ("max_impulse_n_s", |p| p.max_impulse),
    ];
    let mut fields = vec![
        Field::new("point", DataType::UInt32, false),
        Field::new("parcel", DataType::UInt64, false),
        Field::new("stream_time_s", DataType::Float64, false),
    ];
    fields.extend(
        floats
            .iter()
            .map(|(n, _)| Field::new(*n, DataType::Float64, false)),
    );
    fields.extend([
        Field::new("destination", DataType::UInt32, true),
        Field::new("outcome", DataType::Utf8, false),
        Field::new("reason", DataType::Utf8, true),
        Field::new("decided_at", DataType::UInt32, true),
        Field::new("struck", DataType::UInt32, false),
        Field::new("collision_time_s", DataType::Float64, true),
        Field::new("collision_x_m", DataType::Float64, true),
        Field::new("collision_y_m", DataType::Float64, true),
        Field::new("collision_with", DataType::UInt64, true),
    ]);
    let schema = Arc::new(Schema::new(fields));
    let mut writer = ArrowWriter::try_new(
        Vec::new(),
        schema.clone(),
        Some(crate::samples::properties()),
    )
    .map_err(Error::io)?;
    for (i, res) in rows.iter().enumerate() {
        debug_assert_eq!(res.log.len(), res.tally.parcels);
        let mut parcels = res.log.parcels(res.line);
        // The stream's own clock: arrival_s restarts in every segment, this does not.
        let mut clock = 0.0;
        loop {
            let chunk = parcels
                .by_ref()
                .take(PARCEL_BATCH)
                .collect::<Result<Vec<LineParcel>, _>>()
                .map_err(Error::failed)?;
            if chunk.is_empty() {
                break;
            }
            let chunk = &chunk[..];
            let n = chunk.len();
            let mut cols: Vec<ArrayRef> = vec![
                Arc::new(UInt32Array::from_iter_values(std::iter::repeat_n(
                    i as u32, n,
                ))),
                Arc::new(UInt64Array::from_iter_values(chunk.iter().map(|p| p.index))),
                Arc::new(Float64Array::from_iter_values(chunk.iter().map(|p| {
                    let t = clock;
                    clock += p.headway;
                    t
                }))),
            ];
            for (_, f) in &floats {
                cols.push(Arc::new(Float64Array::from_iter_values(
                    chunk.iter().map(f),
                )));
            }
            let opt_u32 = |f: &dyn Fn(&LineParcel) -> Option<u32>| {
                let mut b = UInt32Builder::with_capacity(n);
                for p in chunk {
                    b.append_option(f(p));
                }
                Arc::new(b.finish()) as ArrayRef
            };
            cols.push(opt_u32(&|p| p.destination.map(|d| u32::from(d) + 1)));
            let mut outcome = StringBuilder::new();
            let mut reason = StringBuilder::new();
            for p in chunk {
                outcome.append_value(p.outcome.label());
                reason.append_option(p.outcome.reason());
            }
            cols.push(Arc::new(outcome.finish()));
            cols.push(Arc::new(reason.finish()));
            cols.push(opt_u32(&|p| p.decided_at.map(|d| u32::from(d) + 1)));
            cols.push(Arc::new(UInt32Array::from_iter_values(
                chunk.iter().map(|p| u32::from(p.struck)),
            )));
            let opt_f = |f: &dyn Fn(&Collision) -> f64| {
                let mut b = Float64Builder::with_capacity(n);
                for p in chunk {
                    b.append_option(p.collision.as_ref().map(f));
                }
                Arc::new(b.finish()) as ArrayRef
            };
            cols.push(opt_f(&|c| c.time));
            cols.push(opt_f(&|c| c.x));
            cols.push(opt_f(&|c| c.y));
            cols.push(Arc::new(UInt64Array::from_iter(
                chunk.iter().map(|p| p.collision.map(|c| c.other)),
            )));
            let batch = RecordBatch::try_new(schema.clone(), cols).map_err(Error::io)?;
            writer.write(&batch).map_err(Error::io)?;
        }
    }
    writer.into_inner().map_err(Error::io)
}
