//! The photon pass on the device (photon_pass.wgsl and the grid it feeds): the trace of a
//! pass's paths in as few batches as the binding limit allows, each batch's deposits filed in
//! a grid and folded into the accumulators of the slots that gather them; and what local
//! mode's corrections add to it: the crossed paths listed for pose B, pose A answered from
//! the kept paths of the ordinary pass before it, and pose A's deposits held for pose B's to
//! join, so that one map and one search serve both.

use super::*;
use crate::layout::PHOTON_MARK_CANCELLED;

/// A correction's pose-A deposits, first in the deposit buffers, held for its pose B's to join
/// ([`WgpuBackend::fold_held`] files them alone where they cannot).
#[derive(Clone, Copy, Debug)]
pub(crate) struct HeldDeposits {
    /// How many.
    count: u32,
    /// The gather kind and floor they were traced for.
    gather_kind: u32,
    r2_floor: f32,
}

/// Deposits to file in the grid and fold into the slots' accumulators.
struct Filed<'a> {
    /// How many, held ones included.
    count: u32,
    /// How many of them an earlier pass holds.
    held: u32,
    /// The words beside each and how many each.
    words: (&'a wgpu::Buffer, u32),
    /// The gather kind and floor they are for.
    gather: (u32, f32),
    /// How the accumulation reads them.
    stage: GatherStage,
    /// Leave out the deposits marked as pairs that cancel ([`PHOTON_MARK_CANCELLED`]).
    leave_out: bool,
}

impl WgpuBackend {
    /// Deposit buffers holding at least `capacity` records (reused when large enough, the
    /// first `held` deposits and their ranks copied where they grow), and `words` per deposit
    /// beside them (a path weight, or a pose-A partner's four).
    fn deposit_buffers(
        &mut self,
        capacity: u32,
        words: u32,
        held: u32,
    ) -> Result<(), BackendError> {
        if self.deposits.as_ref().is_none_or(|d| d.capacity < capacity) {
            let grown = DepositBuffers {
                photons: storage_zeroed(&self.ctx, "photons", photon_bytes(capacity))?,
                ranks: storage_zeroed(&self.ctx, "ranks", u64::from(capacity.max(1)) * 4)?,
                weights: None,
                capacity,
            };
            if let Some(old) = self.deposits.as_ref().filter(|_| held > 0) {
                self.run("held deposits copy", |encoder| {
                    let bytes = u64::from(held) * size_of::<Photon>() as u64;
                    encoder.copy_buffer_to_buffer(&old.photons, 0, &grown.photons, 0, bytes);
                    let bytes = u64::from(held) * 4;
                    encoder.copy_buffer_to_buffer(&old.ranks, 0, &grown.ranks, 0, bytes);
                    Ok(())
                })?;
            }
            self.deposits = Some(grown);
        }
        let deposits = self.deposits.as_mut().expect("allocated above");
        let bytes = u64::from(deposits.capacity.max(1)) * u64::from(words) * 4;
        if bytes > deposits.weights.as_ref().map_or(0, wgpu::Buffer::size) {
            deposits.weights = Some(storage_zeroed(&self.ctx, "weights", bytes)?);
        }
        Ok(())
    }

    /// Lists the paths of a culling pass of ordinary photons that its mask says crossed a
    /// box (photon_list_crossed_main), and returns how many; `None` for any other pass.
    fn list_crossed(
        &mut self,
        params: &PhotonPassParams,
        emission: u32,
    ) -> Result<Option<u32>, BackendError> {
        let culls = params.flags & photon_flags::CULL_UNCROSSED != 0;
        if !culls || emission != emission_kind::ORDINARY {
            return Ok(None);
        }
        self.fit_listed_paths(params)?;
        let buffers = (&self.crossed, &self.listed_paths, &self.counters);
        let counters = self.run("crossed-path list", |encoder| {
            self.kernels
                .photon
                .record_list(&self.ctx, encoder, params, buffers);
            Ok(())
        })?;
        Ok(Some(counters[COUNTER_ITEMS]))
    }

    /// Grows the list of paths to hold every path of a pass of `params`.
    fn fit_listed_paths(&mut self, params: &PhotonPassParams) -> Result<(), BackendError> {
        let bytes = u64::from(params.photon_count.max(1)) * 4;
        if self.listed_paths.size() < bytes {
            self.listed_paths = storage_zeroed(&self.ctx, "listed paths", bytes)?;
        }
        Ok(())
    }

    /// Grows the crossed-path mask, keeping its bits and setting the new ones, to hold those
    /// a pass that records it writes; refused, with the limit named, past the binding limit
    /// or 2^32 bits.
    fn fit_crossed_mask(&mut self, params: &PhotonPassParams) -> Result<(), BackendError> {
        if params.flags & photon_flags::RECORD_CROSSED == 0 {
            return Ok(());
        }
        let bytes = crossed_mask_words(params)? * 4;
        if self.crossed.size() >= bytes {
            return Ok(());
        }
        let grown = storage_zeroed(&self.ctx, "crossed", bytes)?;
        // Bits no pass recorded are set: a pass that culls without its record traces all.
        let fresh = vec![0xff_u8; (grown.size() - self.crossed.size()) as usize];
        self.ctx
            .queue
            .write_buffer(&grown, self.crossed.size(), &fresh);
        let old = &self.crossed;
        self.run("crossed-path mask growth", |encoder| {
            encoder.copy_buffer_to_buffer(old, 0, &grown, 0, old.size());
            Ok(())
        })?;
        self.crossed = grown;
        Ok(())
    }

    /// Grows the record of pose A's deposits to hold those of the paths a pairing pass
    /// records ([`photon_flags::RECORD_DEPOSITS`]), zeroed (a zero record pairs nothing).
    fn fit_partners(&mut self, params: &PhotonPassParams) -> Result<(), BackendError> {
        if params.flags & photon_flags::RECORD_DEPOSITS == 0 {
            return Ok(());
        }
        let bytes = crossed_mask_words(params)? * 32 * size_of::<PathDeposits>() as u64;
        if bytes > self.ctx.binding_limit() {
            return Err(BackendError::Limit(format!(
                "pose A's paired deposits: {bytes} bytes exceed the device's binding limit of {}",
                self.ctx.binding_limit()
            )));
        }
        if self.partners.size() < bytes {
            self.partners = storage_zeroed(&self.ctx, "partners", bytes)?;
        }
        Ok(())
    }

    /// Traces a pass whose photons start as `source` says, in as few batches as the device's
    /// binding limit allows (one, unless the deposits would not fit one buffer), and
    /// accumulates each batch into the accumulators of the slots that gather the kind the
    /// pass names, so the gather that follows makes one update for the whole pass.
    pub(crate) fn trace_pass(
        &mut self,
        params: &PhotonPassParams,
        source: &PhotonSource<'_>,
    ) -> Result<PhotonStats, BackendError> {
        self.fit_crossed_mask(params)?;
        self.fit_partners(params)?;
        let limit = self.ctx.binding_limit().min(self.photon_buffer_limit);
        let max_deposits = (limit / size_of::<Photon>() as u64).clamp(1, u64::from(u32::MAX));
        // A deposit's rank, (path - first_path) * max_depth + bounce, must fit 32 bits.
        let rank_paths = u32::MAX / params.max_depth.max(1);
        let mut batch = params.photon_count.clamp(1, rank_paths);
        // No light, no photon: the pass emits its count and its map stays empty.
        let lit = self.scene("photon")?.light_count > 0;
        let emitter = source.emitter();
        let emission = emitter.kind;
        let weighted = source.keeps_weights();
        // A pairing pose B writes each deposit's partner, four words, where weights would go.
        let paired = params.flags & photon_flags::PAIR_DEPOSITS != 0;
        // Only local mode's correction passes test the movers' boxes (and pair deposits).
        let movers = params.flags
            & (photon_flags::CHANGED_ONLY
                | photon_flags::RECORD_CROSSED
                | photon_flags::RECORD_DEPOSITS
                | photon_flags::PAIR_DEPOSITS)
            != 0;
        let spec = self.specialisation(movers);
        // Device times name a local correction's submissions apart from ordinary passes', and
        // its pose B (added to pose A's photons) apart from its pose A.
        let adds = params.flags & photon_flags::ADD_TO_MAP != 0;
        let (trace_name, map_name) = match (movers, adds) {
            (false, _) => ("photon trace", "photon map"),
            (true, false) => ("correction trace, pose A", "correction map, pose A"),
            (true, true) => ("correction trace, pose B", "correction map, pose B"),
        };
        let emitter = buffers::uniform(&self.ctx, "emitter", &emitter);
        let recorded = buffers::storage_init(&self.ctx, "recorded", source.paths());
        let mut stats = PhotonStats {
            emitted: u64::from(params.photon_count),
            ..Default::default()
        };
        let mut map = None;
        let mut batches = 0;
        let mut start = 0;
        // A culling pass of ordinary photons launches only the paths it traces, listed first;
        // one split into batches culls by the mask.
        let mut listed = match lit && batch == params.photon_count {
            true => self.list_crossed(params, emission)?,
            false => None,
        };
        // A pose-A correction of the pass whose paths were kept is answered from them; an
        // ordinary pass that asks keeps its own where they fit.
        let mut replay = self.answer_from_kept_paths(params, source)?;
        let segment_bytes = kept_paths::segment_bytes(params);
        let keeps = lit
            && self.keep_paths
            && KeptPass::wanted(params, source)
            && batch == params.photon_count
            && segment_bytes <= limit;
        if keeps && self.path_segments.size() < segment_bytes {
            self.path_segments = storage_zeroed(&self.ctx, "path segments", segment_bytes)?;
        }
        let mut kept = false;
        // Pose A of a correction holds its deposits for pose B's, which join them in one map;
        // any other pass lets them go (an ordinary pass starts the sums over).
        let mut hold =
            std::mem::take(&mut self.hold_next) && !weighted && batch == params.photon_count;
        if !adds {
            self.held = None;
        }
        let mut base = self.held.map_or(0, |held| held.count);
        let (accumulated, _, _) = self.gather_state("photon")?;
        // A pass added to the last one accumulates onto its sums; any other starts them over.
        let same = Some((params.gather_kind, params.gather_r2_floor.to_bits()));
        if !adds {
            self.run("photon accumulator reset", |encoder| {
                encoder.clear_buffer(accumulated, 0, None);
                Ok(())
            })?;
        } else if self.unconsumed != same || weighted {
            return Err(BackendError::OutOfOrder {
                pass: "photon (added to the map)",
                needs: "an unconsumed photon pass of the same gather kind and floor, without path weights",
            });
        }
        while start < params.photon_count {
            let launch = PhotonPassParams {
                photon_count: batch.min(params.photon_count - start),
                first_path: params.first_path + start,
                ..*params
            };
            // The listed paths hold all the deposits the pass stores.
            let expected = f64::from(launch.photon_count) * self.deposits_per_path * 1.25 + 256.0;
            let (launch, kind) = match listed {
                Some(count) => (
                    PhotonPassParams {
                        photon_count: count,
                        ..launch
                    },
                    Launch::Listed,
                ),
                None => (launch, Launch::Range),
            };
            let capacity = (expected + f64::from(base)).min(max_deposits as f64) as u32;
            let words_each = if paired { 4 } else { u32::from(weighted) };
            self.deposit_buffers(capacity, words_each, base)?;
            self.grid_buffers = Some(GridBuffers::fit(
                &self.ctx,
                self.grid_buffers.take(),
                capacity,
            )?);
            let scene = self.scene("photon")?;
            let deposits = self.deposits.as_ref().expect("allocated above");
            let weights = deposits.weights.as_ref().unwrap_or(&self.no_weights);
            // A deposit's index must stay exact in its kept segment's f32 word.
            let keep = keeps && deposits.capacity <= kept_paths::MOST_DEPOSITS;
            let launch = PhotonPassParams {
                flags: match keep {
                    true => launch.flags,
                    false => launch.flags & !photon_flags::KEEP_PATHS,
                },
                ..launch
            };
            // A pairing pose B joining pose A's unfiled deposits marks the pairs that cancel,
            // and its map leaves them out.
            let marks = paired && base > 0 && self.held.is_some();
            let launch = PhotonPassParams {
                flags: match marks {
                    true => launch.flags | PHOTON_MARK_CANCELLED,
                    false => launch.flags,
                },
                ..launch
            };
            // The kept segments take the place of the words an ordinary pass writes none of.
            let written = if keep { &self.path_segments } else { weights };
            let targets = PhotonTargets {
                ranks: &deposits.ranks,
                photons: &deposits.photons,
                counters: &self.counters,
                emitter: &emitter,
                recorded: &recorded,
                weights: written,
                crossed: &self.crossed,
                partners: &self.partners,
                listed_paths: &self.listed_paths,
            };
            let traced = if let Some(sign) = replay.filter(|_| lit) {
                self.replay_pass(&launch, sign, spec, &targets)?
            } else if lit {
                // Deposits joining held ones go after them, with no words beside those.
                let from = [0, base, 0, u32::MAX];
                self.run_from(trace_name, from, |encoder| {
                    if base > 0 && words_each > 0 {
                        let bytes = u64::from(base) * u64::from(words_each) * 4;
                        encoder.clear_buffer(weights, 0, Some(bytes));
                    }
                    let launched = (emission, kind);
                    self.kernels
                        .photon
                        .record(&self.ctx, encoder, &launch, scene, &targets, launched, spec);
                    Ok(())
                })?
            } else {
                [0, base, 0, u32::MAX]
            };
            let deposited = traced[COUNTER_ITEMS];
            if deposited > deposits.capacity {
                // The buffers were too small: grow them, or split the pass if even the
                // binding limit cannot hold the batch (then by the mask); this trace is
                // discarded. The paths the batch covers, listed or not, made its deposits. (A
                // replay stores a part of what its kept pass stored, which fitted: traced again
                // if it did not.)
                replay = None;
                let paths = batch.min(params.photon_count - start);
                self.deposits_per_path = f64::from(deposited - base) / f64::from(paths);
                if u64::from(deposited) > max_deposits && launch.photon_count == 1 {
                    return Err(BackendError::Limit(format!(
                        "one photon path deposits {deposited} photons; the photon buffer holds {max_deposits}"
                    )));
                }
                if u64::from(deposited) > max_deposits {
                    batch = ((u64::from(paths) * max_deposits / u64::from(deposited)) * 9 / 10)
                        .max(1) as u32;
                    listed = None;
                    // Batches each build their own map: the held deposits get theirs first,
                    // and a pass of several holds none.
                    self.fold_held()?;
                    base = 0;
                    hold = false;
                }
                continue;
            }
            if hold {
                // Filed with pose B's, which join them.
                self.held = Some(HeldDeposits {
                    count: deposited,
                    gather_kind: params.gather_kind,
                    r2_floor: params.gather_r2_floor,
                });
                stats.deposited += u64::from(deposited);
                stats.rays += u64::from(traced[COUNTER_RAYS]);
                batches += 1;
                break;
            }
            let filed = Filed {
                count: deposited,
                held: base,
                words: (weights, words_each),
                gather: (params.gather_kind, params.gather_r2_floor),
                stage: GatherStage::Accumulate { weighted, paired },
                leave_out: marks,
            };
            map = Some(self.file_and_fold(map_name, &filed)?);
            kept = keep;
            self.held = None;
            stats.deposited += u64::from(deposited - base);
            stats.rays += u64::from(traced[COUNTER_RAYS]);
            stats.culled += u64::from(traced[COUNTER_CULLED]);
            start += match listed {
                Some(count) => {
                    stats.culled += u64::from(params.photon_count - count);
                    params.photon_count
                }
                None => launch.photon_count,
            };
            batches += 1;
        }
        if params.photon_count > 0 {
            self.deposits_per_path =
                (stats.deposited as f64 / f64::from(params.photon_count)).max(0.1);
        }
        self.map = map;
        self.map_kind = params.gather_kind;
        self.unconsumed = same.filter(|_| !weighted);
        self.batches = batches;
        self.last_pass_paths = params.first_path + params.photon_count;
        if kept && batches == 1 {
            self.kept_paths = Some(KeptPaths {
                pass: KeptPass::of(params),
                pose: self.scene("photon")?.pose(),
                deposits: stats.deposited as u32,
            });
        }
        Ok(stats)
    }

    /// Files `filed`'s deposits, held ones first, in the grid, and folds them into the
    /// accumulators of the slots that gather their kind, in one submission named `name`.
    fn file_and_fold(&self, name: &'static str, filed: &Filed) -> Result<PhotonMap, BackendError> {
        let scene = self.scene("photon")?;
        let deposits = self.deposits.as_ref().ok_or(BackendError::OutOfOrder {
            pass: name,
            needs: "a photon pass",
        })?;
        let grid_buffers = self.grid_buffers.as_ref().ok_or(BackendError::OutOfOrder {
            pass: name,
            needs: "a photon pass",
        })?;
        let (hit_points, slots) = self.hit_points("photon")?;
        let (accumulated, pending, r2_initial) = self.gather_state("photon")?;
        let slots = Slots {
            hit_points,
            counters: &self.counters,
            count: *slots,
        };
        let (kind, r2_floor) = filed.gather;
        let accumulate = GatherParams {
            kind,
            ..GatherParams::default()
        };
        let radii = radii(&self.ctx, r2_initial, r2_floor);
        let gather = GatherInputs {
            params: &accumulate,
            table: &scene.table,
            accumulated,
            pending,
            radii: &radii,
        };
        let (weights, words) = filed.words;
        let mut map = None;
        self.run(name, |encoder| {
            let built = self.kernels.grid.record(
                &self.ctx,
                encoder,
                &self.kernels.scan,
                grid_buffers,
                (
                    deposits.photons.clone(),
                    (weights.clone(), words),
                    &deposits.ranks,
                    filed.count,
                ),
                (hit_points, slots.count),
                (r2_floor, filed.held, filed.leave_out),
            )?;
            self.kernels
                .gather
                .record(&self.ctx, encoder, &gather, &built, &slots, filed.stage);
            map = Some(built);
            Ok(())
        })?;
        Ok(map.expect("recorded above"))
    }

    /// Files and folds the deposits a correction's pose A holds, where it holds some, as its
    /// own map: before anything but its pose B reads the accumulators, or when pose B cannot
    /// join them in one buffer.
    pub(crate) fn fold_held(&mut self) -> Result<(), BackendError> {
        let Some(held) = self.held.take() else {
            return Ok(());
        };
        let filed = Filed {
            count: held.count,
            held: 0,
            words: (&self.no_weights, 0),
            gather: (held.gather_kind, held.r2_floor),
            stage: GatherStage::Accumulate {
                weighted: false,
                paired: false,
            },
            leave_out: false,
        };
        self.map = Some(self.file_and_fold("correction map, pose A", &filed)?);
        self.map_kind = held.gather_kind;
        Ok(())
    }

    /// Whether ordinary passes keep their paths where asked (the default), or a local move's
    /// pose A traces its correction photons: the same slots bit for bit, which a test holds it
    /// to.
    pub fn set_keep_paths(&mut self, keep: bool) {
        self.keep_paths = keep;
    }

    /// The sign of the kept deposits, where the last pass kept its paths and they answer the
    /// pass `params` from `source` in the pose held; its deposits are then copied aside, as
    /// the answer writes its own over them. Any pass forgets the kept paths.
    fn answer_from_kept_paths(
        &mut self,
        params: &PhotonPassParams,
        source: &PhotonSource<'_>,
    ) -> Result<Option<f32>, BackendError> {
        let pose = self.scene("photon")?.pose();
        let Some(kept) = self.kept_paths.take() else {
            return Ok(None);
        };
        let Some(sign) = kept.answers(params, source, pose) else {
            return Ok(None);
        };
        // The paths too long to keep are listed to be traced again.
        self.fit_listed_paths(params)?;
        let Some(deposits) = &self.deposits else {
            return Ok(None);
        };
        let bytes = photon_bytes(kept.deposits);
        if self.kept_photons.size() < bytes {
            self.kept_photons = storage_zeroed(&self.ctx, "kept photons", bytes)?;
        }
        self.run("kept deposits copy", |encoder| {
            encoder.copy_buffer_to_buffer(&deposits.photons, 0, &self.kept_photons, 0, bytes);
            Ok(())
        })?;
        self.ctx.scoped("shader compilation", || {
            self.kernels.moves.replay(&self.ctx);
        })?;
        Ok(Some(sign))
    }

    /// The pass `launch` answered from the kept paths, their deposits times `sign`
    /// (path_replay.wgsl), and the paths too long to keep traced again, counting on; returns
    /// the counters as a trace does.
    fn replay_pass(
        &self,
        launch: &PhotonPassParams,
        sign: f32,
        spec: Specialisation,
        targets: &PhotonTargets,
    ) -> Result<[u32; 4], BackendError> {
        let kernel = self.kernels.moves.replay(&self.ctx);
        let scene = self.scene("correction replay, pose A")?;
        let replayed = PhotonPassParams {
            power_scale: sign,
            ..*launch
        };
        let counters = self.run("correction replay, pose A", |encoder| {
            let kept = (&self.path_segments, &self.kept_photons);
            kernel.record(&self.ctx, encoder, (&replayed, scene), kept, targets);
            Ok(())
        })?;
        let longer = counters[COUNTER_LISTED];
        if longer == 0 {
            return Ok(counters);
        }
        let retrace = PhotonPassParams {
            photon_count: longer,
            ..*launch
        };
        let from = [0, counters[COUNTER_ITEMS], 0, u32::MAX];
        self.run_from("correction trace, pose A", from, |encoder| {
            let launched = (emission_kind::ORDINARY, Launch::Listed);
            self.kernels
                .photon
                .record(&self.ctx, encoder, &retrace, scene, targets, launched, spec);
            Ok(())
        })
    }
}

impl PhotonPass for WgpuBackend {
    fn photon_pass(
        &mut self,
        params: &PhotonPassParams,
        source: &PhotonSource<'_>,
    ) -> Result<PhotonStats, BackendError> {
        self.trace_pass(params, source)
    }
}
