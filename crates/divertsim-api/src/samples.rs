//! The sample table of a reliability run: one row per sample (its inputs, outcome, reason,
//! stages, divert reserve and overload), as Arrow record batches written to Parquet (and CSV
//! on request). The same encoding is the run's checkpoint: a shard's Parquet file decodes
//! back to exactly the samples that were run (every float stored as f64 bits), so a resumed
//! run tallies exactly what an uninterrupted one does.
//!
//! Columns carry their unit in the name (SI; the angle in radians, as stored).

use crate::contract::Error;
use arrow_array::builder::{Float64Builder, StringBuilder, UInt32Builder};
use arrow_array::{
    Array, ArrayRef, Float64Array, RecordBatch, StringArray, UInt32Array, UInt64Array,
};
use arrow_schema::{DataType, Field, Schema, SchemaRef};
use divertsim_core::analysis::population::mix::Draw;
use divertsim_core::analysis::population::reliability::{
    sequence_label, stored_inputs, SampleRun, INPUT_NAMES,
};
use divertsim_core::analysis::population::reliability::{RunPlan, ShardStore};
use divertsim_core::run::memo::{self, Memo};
use divertsim_core::sim::{NotDivertedReason, Outcome, Stage};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use parquet::arrow::ArrowWriter;
use parquet::basic::Compression;
use parquet::file::properties::WriterProperties;
use std::fs::File;
use std::path::Path;
use std::sync::Arc;

const REJECTED: [&str; 5] = [
    "rejected_off_belt",
    "rejected_size",
    "rejected_mass",
    "rejected_material",
    "rejected_arrival",
];
const FLOATS_OUT: [&str; 5] = [
    "max_lateral_m",
    "divert_reserve_m",
    "max_impulse_n_s",
    "overload_ratio",
    "tipping_margin",
];

/// The table's schema.
pub fn schema() -> SchemaRef {
    let mut fields = vec![
        Field::new("sample", DataType::UInt64, false),
        Field::new("point", DataType::UInt32, false),
    ];
    for (name, _) in INPUT_NAMES {
        // μ_b is null where the mix does not scatter it (the scenario's law applies).
        fields.push(Field::new(name, DataType::Float64, name == "belt_friction"));
    }
    for name in REJECTED {
        fields.push(Field::new(name, DataType::UInt32, false));
    }
    fields.push(Field::new("outcome", DataType::Utf8, false));
    fields.push(Field::new("reason", DataType::Utf8, true));
    fields.push(Field::new("failure_message", DataType::Utf8, true));
    fields.push(Field::new("final_stage", DataType::Utf8, false));
    fields.push(Field::new("stages", DataType::Utf8, false));
    fields.push(Field::new("strikes", DataType::UInt32, false));
    for name in FLOATS_OUT {
        fields.push(Field::new(name, DataType::Float64, false));
    }
    // Null without an arm or for a run that failed.
    fields.push(Field::new("arm_peak_torque_n_m", DataType::Float64, true));
    // Each strike's |J_c| about the pivot, ';'-separated in time order.
    fields.push(Field::new(
        "arm_strike_impulses_n_m_s",
        DataType::Utf8,
        false,
    ));
    // Tipped over (its centre of mass passed over an edge); `tipping_margin` below 1 only
    // says an edge lifted.
    fields.push(Field::new("tipped", DataType::Boolean, false));
    Arc::new(Schema::new(fields))
}

/// The samples of point `point` as one record batch.
pub fn to_batch(point: usize, samples: &[SampleRun]) -> Result<RecordBatch, Error> {
    let n = samples.len();
    let mut cols: Vec<ArrayRef> = Vec::new();
    cols.push(Arc::new(UInt64Array::from_iter_values(
        samples.iter().map(|s| s.draw.index),
    )));
    cols.push(Arc::new(UInt32Array::from_iter_values(
        std::iter::repeat_n(point as u32, n),
    )));
    for k in 0..INPUT_NAMES.len() {
        let mut b = Float64Builder::with_capacity(n);
        for s in samples {
            b.append_option(stored_inputs(s)[k]);
        }
        cols.push(Arc::new(b.finish()));
    }
    for k in 0..REJECTED.len() {
        let mut b = UInt32Builder::with_capacity(n);
        for s in samples {
            b.append_value(s.draw.rejected[k]);
        }
        cols.push(Arc::new(b.finish()));
    }
    let strings = |f: &dyn Fn(&SampleRun) -> Option<String>| {
        let mut b = StringBuilder::new();
        for s in samples {
            b.append_option(f(s));
        }
        Arc::new(b.finish()) as ArrayRef
    };
    cols.push(strings(&|s| Some(s.outcome.label().to_string())));
    cols.push(strings(&|s| s.reason().map(str::to_string)));
    cols.push(strings(&|s| match &s.outcome {
        Outcome::Failed(m) => Some(m.clone()),
        _ => None,
    }));
    cols.push(strings(&|s| Some(s.final_stage.label().to_string())));
    cols.push(strings(&|s| Some(sequence_label(&s.stages))));
    let mut b = UInt32Builder::with_capacity(n);
    for s in samples {
        b.append_value(s.strikes);
    }
    cols.push(Arc::new(b.finish()));
    for f in [
        |s: &SampleRun| s.max_lateral,
        |s: &SampleRun| s.reserve,
        |s: &SampleRun| s.max_impulse,
        |s: &SampleRun| s.overload_ratio,
        |s: &SampleRun| s.tipping_margin,
    ] {
        cols.push(Arc::new(Float64Array::from_iter_values(
            samples.iter().map(f),
        )));
    }
    cols.push(Arc::new(Float64Array::from_iter(
        samples.iter().map(|s| s.arm_peak_torque),
    )));
    cols.push(strings(&|s| Some(impulses_text(&s.arm_strike_impulses))));
    cols.push(Arc::new(arrow_array::BooleanArray::from_iter(
        samples.iter().map(|s| Some(s.tipped_over)),
    )));
    RecordBatch::try_new(schema(), cols).map_err(Error::io)
}

/// Strike impulses as text: each in the shortest form that reads back exactly, ';' between.
fn impulses_text(j: &[f64]) -> String {
    j.iter().map(f64::to_string).collect::<Vec<_>>().join(";")
}

fn column<'a, T: 'static>(batch: &'a RecordBatch, name: &str) -> Result<&'a T, Error> {
    batch
        .column_by_name(name)
        .and_then(|c| c.as_any().downcast_ref::<T>())
        .ok_or_else(|| Error::Io(format!("column {name} is missing or of the wrong type")))
}

/// The samples of a record batch (the inverse of [`to_batch`]).
pub fn from_batch(batch: &RecordBatch) -> Result<Vec<SampleRun>, Error> {
    let sample: &UInt64Array = column(batch, "sample")?;
    let floats: Vec<&Float64Array> = INPUT_NAMES
        .iter()
        .map(|(n, _)| column(batch, n))
        .collect::<Result<_, _>>()?;
    let rejected: Vec<&UInt32Array> = REJECTED
        .iter()
        .map(|n| column(batch, n))
        .collect::<Result<_, _>>()?;
    let outs: Vec<&Float64Array> = FLOATS_OUT
        .iter()
        .map(|n| column(batch, n))
        .collect::<Result<_, _>>()?;
    let outcome: &StringArray = column(batch, "outcome")?;
    let reason: &StringArray = column(batch, "reason")?;
    let message: &StringArray = column(batch, "failure_message")?;
    let final_stage: &StringArray = column(batch, "final_stage")?;
    let stages: &StringArray = column(batch, "stages")?;
    let strikes: &UInt32Array = column(batch, "strikes")?;
    let peak_torque: &Float64Array = column(batch, "arm_peak_torque_n_m")?;
    let strike_impulses: &StringArray = column(batch, "arm_strike_impulses_n_m_s")?;
    let tipped: &arrow_array::BooleanArray = column(batch, "tipped")?;
    let stage =
        |l: &str| Stage::from_label(l).ok_or_else(|| Error::Io(format!("unknown stage {l:?}")));
    (0..batch.num_rows())
        .map(|i| {
            let f = |k: usize| floats[k].value(i);
            let outcome = match outcome.value(i) {
                "diverted" => Outcome::Diverted,
                "not_diverted" => Outcome::NotDiverted(
                    NotDivertedReason::from_label(reason.value(i))
                        .ok_or_else(|| Error::Io(format!("row {i}: unknown reason")))?,
                ),
                "failed" => Outcome::Failed(message.value(i).to_string()),
                other => return Err(Error::Io(format!("row {i}: unknown outcome {other:?}"))),
            };
            let seq = stages.value(i);
            Ok(SampleRun {
                draw: Draw {
                    index: sample.value(i),
                    length: f(0),
                    width: f(1),
                    height: f(2),
                    mass: f(3),
                    offset: f(4),
                    angle: f(5),
                    speed: f(6),
                    spin: f(7),
                    phase: f(8),
                    belt_friction: (!floats[9].is_null(i)).then(|| f(9)),
                    arm_friction: f(10),
                    restitution: f(11),
                    rejected: std::array::from_fn(|k| rejected[k].value(i)),
                },
                start_position: f(12),
                outcome,
                final_stage: stage(final_stage.value(i))?,
                stages: if seq.is_empty() {
                    Vec::new()
                } else {
                    seq.split('>').map(stage).collect::<Result<_, _>>()?
                },
                strikes: strikes.value(i),
                max_lateral: outs[0].value(i),
                reserve: outs[1].value(i),
                max_impulse: outs[2].value(i),
                overload_ratio: outs[3].value(i),
                tipping_margin: outs[4].value(i),
                tipped_over: tipped.value(i),
                arm_peak_torque: (!peak_torque.is_null(i)).then(|| peak_torque.value(i)),
                arm_strike_impulses: match strike_impulses.value(i) {
                    "" => Vec::new(),
                    text => text
                        .split(';')
                        .map(|v| {
                            v.parse().map_err(|_| {
                                Error::Io(format!("row {i}: bad strike impulse {v:?}"))
                            })
                        })
                        .collect::<Result<_, _>>()?,
                },
            })
        })
        .collect()
}

pub(crate) fn properties() -> WriterProperties {
    WriterProperties::builder()
        .set_compression(Compression::SNAPPY)
        .set_created_by(format!("divertsim {}", env!("CARGO_PKG_VERSION")))
        .build()
}

/// A Parquet file being written, one row group per batch.
pub struct ParquetSink {
    writer: ArrowWriter<File>,
}

impl ParquetSink {
    pub fn create(path: &Path) -> Result<ParquetSink, Error> {
        let file = File::create(path)
            .map_err(|e| Error::Io(format!("cannot create {}: {e}", path.display())))?;
        let writer = ArrowWriter::try_new(file, schema(), Some(properties()))
            .map_err(|e| Error::Io(format!("{}: {e}", path.display())))?;
        Ok(ParquetSink { writer })
    }

    /// Append a batch as its own row group.
    pub fn write(&mut self, batch: &RecordBatch) -> Result<(), Error> {
        self.writer.write(batch).map_err(Error::io)?;
        self.writer.flush().map_err(Error::io)
    }

    /// Finish the file (footer) and sync it to disk.
    pub fn close(self) -> Result<(), Error> {
        let file = self.writer.into_inner().map_err(Error::io)?;
        file.sync_all().map_err(Error::io)
    }
}

/// Write a batch as a complete Parquet file, atomically: a temporary file renamed into
/// place, so `path` either holds the whole shard or does not exist.
pub fn write_file(path: &Path, batch: &RecordBatch) -> Result<(), Error> {
    let tmp = path.with_extension("parquet.tmp");
    let mut sink = ParquetSink::create(&tmp)?;
    sink.write(batch)?;
    sink.close()?;
    std::fs::rename(&tmp, path)
        .map_err(|e| Error::Io(format!("cannot move {} into place: {e}", tmp.display())))
}

/// Every batch of a Parquet file, in order.
pub fn read_file(path: &Path) -> Result<Vec<RecordBatch>, Error> {
    let file =
        File::open(path).map_err(|e| Error::Io(format!("cannot read {}: {e}", path.display())))?;
    let reader = ParquetRecordBatchReaderBuilder::try_new(file)
        // One batch per row group, up to the largest shard, so a merged file keeps one
        // row group per shard.
        .and_then(|b| b.with_batch_size(10_000_000).build())
        .map_err(|e| Error::Io(format!("{}: {e}", path.display())))?;
    reader
        .map(|b| b.map_err(|e| Error::Io(format!("{}: {e}", path.display()))))
        .collect()
}

/// The samples of one shard of point `point` as the bytes of a Parquet file (what a
/// cluster's worker sends back; [`from_parquet_bytes`] reads it exactly).
pub fn to_parquet_bytes(point: usize, samples: &[SampleRun]) -> Result<Vec<u8>, Error> {
    let batch = to_batch(point, samples)?;
    let mut writer =
        ArrowWriter::try_new(Vec::new(), schema(), Some(properties())).map_err(Error::io)?;
    writer.write(&batch).map_err(Error::io)?;
    writer.into_inner().map_err(Error::io)
}

/// The samples in the bytes of a Parquet file of [`schema`].
/// Damaged bytes are an error, never a panic (the parquet reader can panic on some).
pub fn from_parquet_bytes(bytes: Vec<u8>) -> Result<Vec<SampleRun>, Error> {
    from_parquet_bytes_of(bytes, None)
}

/// [`from_parquet_bytes`], with every row's `point` column checked to be `point`.
pub fn from_parquet_bytes_of(
    bytes: Vec<u8>,
    point: Option<usize>,
) -> Result<Vec<SampleRun>, Error> {
    let mut out = Vec::new();
    for b in batches_of_parquet_bytes(bytes, point)? {
        out.extend(from_batch(&b)?);
    }
    Ok(out)
}

/// The record batches in the bytes of a Parquet file of [`schema`], every row's `point`
/// column checked to be `point` where given. Damaged bytes are an error, never a panic.
pub fn batches_of_parquet_bytes(
    bytes: Vec<u8>,
    point: Option<usize>,
) -> Result<Vec<RecordBatch>, Error> {
    let read = || -> Result<Vec<RecordBatch>, Error> {
        let reader = ParquetRecordBatchReaderBuilder::try_new(bytes::Bytes::from(bytes))
            .and_then(|b| b.with_batch_size(10_000_000).build())
            .map_err(Error::io)?;
        let mut out = Vec::new();
        for b in reader {
            let b = b.map_err(Error::io)?;
            if let Some(want) = point {
                let points = column::<UInt32Array>(&b, "point")?;
                if points.iter().any(|p| p.map(|p| p as usize) != Some(want)) {
                    return Err(Error::Io(format!("the samples are not of point {want}")));
                }
            }
            out.push(b);
        }
        Ok(out)
    };
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(read))
        .unwrap_or_else(|_| Err(Error::Io("the shard's Parquet bytes are damaged".into())))
}

/// Append a batch's rows to a CSV writer (header written by the caller); floats in the
/// shortest form that reads back exactly.
pub fn write_csv_rows<W: std::io::Write>(
    w: &mut csv::Writer<W>,
    batch: &RecordBatch,
) -> Result<(), Error> {
    let schema = batch.schema();
    for i in 0..batch.num_rows() {
        let mut row: Vec<String> = Vec::with_capacity(schema.fields().len());
        for (c, field) in schema.fields().iter().enumerate() {
            let col = batch.column(c);
            let cell = if col.is_null(i) {
                String::new()
            } else {
                match field.data_type() {
                    DataType::Float64 => {
                        let a = col
                            .as_any()
                            .downcast_ref::<Float64Array>()
                            .map(|a| a.value(i));
                        a.map(|v| v.to_string()).unwrap_or_default()
                    }
                    DataType::UInt64 => col
                        .as_any()
                        .downcast_ref::<UInt64Array>()
                        .map(|a| a.value(i).to_string())
                        .unwrap_or_default(),
                    DataType::UInt32 => col
                        .as_any()
                        .downcast_ref::<UInt32Array>()
                        .map(|a| a.value(i).to_string())
                        .unwrap_or_default(),
                    _ => col
                        .as_any()
                        .downcast_ref::<StringArray>()
                        .map(|a| a.value(i).to_string())
                        .unwrap_or_default(),
                }
            };
            row.push(cell);
        }
        w.write_record(&row).map_err(Error::io)?;
    }
    Ok(())
}

/// The CSV header: the schema's column names.
pub fn csv_header() -> Vec<String> {
    schema().fields().iter().map(|f| f.name().clone()).collect()
}

// ---------------------------------------------------------------------------------------------
// Shards in a memo.

/// The shards of a run kept in a memo (a command's checkpoint) as the bytes of their
/// Parquet files, one piece per shard under [`MemoShards::key`], checked on reading to hold
/// exactly that shard's samples. For a memo that keeps nothing, nothing is encoded.
pub struct MemoShards<'a> {
    pub memo: &'a dyn Memo,
    /// Each point's name within the run: its swept value, its seed and a digest of what it
    /// is made of (its scenario and mix).
    pub points: Vec<(String, u64, u64)>,
    /// The run the shards belong to.
    pub plan: RunPlan,
}

impl MemoShards<'_> {
    /// The memo key of shard `k` of point `point`.
    pub fn key(&self, point: usize, k: u64) -> u64 {
        memo::key(
            "reliability-shard",
            &(point, self.points.get(point), &self.plan, k),
        )
    }

    /// Shard `k` of point `point` as kept, in record batches as they were written (a
    /// shard of this run: checked when it was read back or kept when it was run), or
    /// `None`.
    pub fn batches(&self, point: usize, k: u64) -> Result<Option<Vec<RecordBatch>>, Error> {
        self.memo
            .recall(self.key(point, k))
            .map(|bytes| batches_of_parquet_bytes(bytes, Some(point)))
            .transpose()
    }
}

impl ShardStore for MemoShards<'_> {
    fn load(&self, point: usize, k: u64) -> Result<Option<Vec<SampleRun>>, String> {
        let Some(bytes) = self.memo.recall(self.key(point, k)) else {
            return Ok(None);
        };
        let out = from_parquet_bytes_of(bytes, Some(point)).map_err(|e| e.to_string())?;
        let want: Vec<u64> = self.plan.shard_range(k).collect();
        if out.iter().map(|s| s.draw.index).ne(want.iter().copied()) {
            return Err(format!(
                "shard {k} of point {point} as kept does not hold samples {}..{}: it is another run's (a checkpoint's: remove it to start over; a cluster's: give each piece under its own key)",
                want.first().copied().unwrap_or(0),
                want.last().map_or(0, |l| l + 1)
            ));
        }
        Ok(Some(out))
    }

    fn save(&self, point: usize, k: u64, s: &[SampleRun]) -> Result<(), String> {
        if self.memo.keeps() {
            let bytes = to_parquet_bytes(point, s).map_err(|e| e.to_string())?;
            self.memo.keep(self.key(point, k), &bytes);
        }
        Ok(())
    }
}

/// The sample table of a run of `shards[p]` shards at point p, each in record batches from
/// `shard(p, k)`, in order, into `out/samples.parquet` (one row group per shard) and, with
/// `csv`, `out/samples.csv`; returns the first `keep` failed samples with their point.
pub fn write_table(
    shards: &[u64],
    mut shard: impl FnMut(usize, u64) -> Result<Vec<RecordBatch>, Error>,
    out: &Path,
    csv: bool,
    keep: usize,
) -> Result<Vec<(usize, SampleRun)>, Error> {
    let mut failed = Vec::new();
    let mut sink = ParquetSink::create(&out.join("samples.parquet"))?;
    let mut csv_out = if csv {
        let p = out.join("samples.csv");
        let mut w =
            csv::Writer::from_path(&p).map_err(|e| Error::Io(format!("{}: {e}", p.display())))?;
        w.write_record(csv_header()).map_err(Error::io)?;
        Some(w)
    } else {
        None
    };
    for (point, &count) in shards.iter().enumerate() {
        for k in 0..count {
            for b in shard(point, k)? {
                sink.write(&b)?;
                // Decoded only while failures are still wanted.
                if failed.len() < keep {
                    failed.extend(
                        from_batch(&b)?
                            .into_iter()
                            .filter(SampleRun::failed)
                            .take(keep - failed.len())
                            .map(|s| (point, s)),
                    );
                }
                if let Some(w) = &mut csv_out {
                    write_csv_rows(w, &b)?;
                }
            }
        }
    }
    if let Some(mut w) = csv_out {
        w.flush().map_err(Error::io)?;
    }
    sink.close()?;
    Ok(failed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use divertsim_core::analysis::population::mix::{MassLaw, ParcelMix, Placement, Sizes};
    use divertsim_core::analysis::population::reliability::{run_shard, StartRule};
    use divertsim_core::model::params::Scenario;
    use divertsim_core::run::sweep::no_progress;
    use divertsim_core::stats::distribution::Distribution;

    #[test]
    fn shard_round_trips_exactly_through_parquet() {
        let s = Scenario::paper_default();
        let mix = ParcelMix {
            sizes: Sizes::Drawn {
                length: Distribution::Uniform { min: 0.2, max: 0.7 },
                width: Distribution::Uniform {
                    min: 0.1,
                    max: 0.26,
                },
                height: Distribution::Fixed(0.1),
            },
            mass: MassLaw::Mass(Distribution::Fixed(2.0)),
            placement: Placement::RoomFraction(Distribution::Uniform { min: 0.0, max: 1.0 }),
            angle: Distribution::Normal { mean: 0.0, sd: 0.2 },
            speed: Distribution::Fixed(0.0),
            spin: Distribution::Fixed(0.0),
            phase: Distribution::Fixed(0.0),
            belt_friction: Some(Distribution::Uniform { min: 0.3, max: 0.5 }),
            arm_friction: None,
            restitution: None,
        };
        let runs = run_shard(&s, &mix, &StartRule::Fixed, 5, 0..30, &no_progress).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.parquet");
        write_file(&p, &to_batch(3, &runs).unwrap()).unwrap();
        let back: Vec<SampleRun> = read_file(&p)
            .unwrap()
            .iter()
            .flat_map(|b| from_batch(b).unwrap())
            .collect();
        assert_eq!(back, runs);
        let bytes = to_parquet_bytes(3, &runs).unwrap();
        assert_eq!(from_parquet_bytes(bytes.clone()).unwrap(), runs);
        // Damaged bytes are an error or other samples, never a panic.
        for k in (0..bytes.len()).step_by(7) {
            let mut bad = bytes.clone();
            bad[k] ^= 0x5a;
            let _ = from_parquet_bytes(bad);
        }
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(csv_header()).unwrap();
        write_csv_rows(&mut w, &to_batch(3, &runs).unwrap()).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(text.lines().count(), 31);
        assert!(text.starts_with("sample,point,length_m"));
    }
}
