// SPDX-License-Identifier: Apache-2.0
// The gauge's evaluation: one thread at a time, sheets in order. A
// sheet_job's rows become a flt_sheet: counts and coverage, the flatness
// metrics, the strip's width and position, the verdict against the rules,
// the coil's statistics, the archive; then it is delivered.
#include "gauge/gauge_internal.hpp"

namespace flt {

using namespace gauge_detail;

flt_sheet *gauge::take_slot(std::size_t rows) {
    {
        std::lock_guard<std::mutex> lock(pool_->m);
        if (!pool_->free.empty()) {
            flt_sheet *sh = pool_->free.back();
            pool_->free.pop_back();
            pool_->out.fetch_add(1);
            return sh;
        }
    }
    if (cfg_.sheet_backlog == 0) {
        // The caller chose to keep no backlog: the oldest waiting sheet
        // makes room for the newest.
        std::unique_lock<std::mutex> lock(m_);
        ++n_sheets_dropped_;
        const unsigned long long dropped = n_sheets_dropped_;
        if (ready_count_ == 0) {
            lock.unlock();
            FLT_LOG(FLT_LOG_WARNING, "gauge",
                    "a finished sheet was dropped: every sheet slot is held by the caller "
                    "(gauge_sheet_backlog = 0; %llu sheets dropped so far)",
                    dropped);
            return nullptr;  // every slot is held by the caller: this sheet is lost
        }
        flt_sheet *sh = ready_[ready_head_];
        ready_head_ = (ready_head_ + 1) % ready_.size();
        --ready_count_;
        return sh;
    }
    // Every slot is taken: a sheet of its own (maps of its rows only),
    // freed when it is given back. Never a finished sheet dropped.
    auto sh = std::make_unique<flt_sheet>();
    sh->pool = pool_;
    sh->grown = true;
    sh->fibers = K_;
    sh->maps = cfg_.keep_maps;
    for (int a = 0; a < k_sheet_arrays; ++a)
        sh->array[a].assign(is_fiber_array(a) ? K_ : zones_, 0.0);
    if (cfg_.keep_maps >= 1) {
        sh->map_s.assign(rows, 0.0);
        sh->map_z.assign(rows * K_, 0.0);
        sh->map_flags.assign(rows * K_, 0);
    }
    if (cfg_.keep_maps >= 2)
        sh->map_measured.assign(rows * K_, 0.0);
    pool_->out.fetch_add(1);
    unsigned long long grown = 0;
    {
        std::lock_guard<std::mutex> lock(m_);
        grown = ++n_sheets_grown_;
    }
    FLT_LOG(FLT_LOG_INFO, "gauge",
            "every one of the %zu sheet slots is taken: another sheet made (%llu so far; read "
            "the sheets sooner, or raise gauge_sheet_slots)",
            cfg_.sheet_slots, grown);
    return sh.release();
}

namespace {

// One rule's coil statistics as the FLT_COIL_* values (gauge.h), for
// flt_gauge_coil_rule and for the archive's copy at a coil's end: one
// place, so both always carry the same values.
void coil_rule_values(const coil_stats &c, const coil_stats::per_rule &p, double *a) {
    a[FLT_COIL_NUMBER] = c.coil;
    a[FLT_COIL_SHEETS] = c.sheets;
    a[FLT_COIL_SHEETS_PASSED] = c.passed;
    a[FLT_COIL_SHEETS_FAILED] = c.failed;
    a[FLT_COIL_FINISHED] = c.finished ? 1.0 : 0.0;
    a[FLT_COIL_RULES] = double(c.rules.size());
    a[FLT_COIL_RULE_PASSED] = p.count[FLT_VERDICT_PASS];
    a[FLT_COIL_RULE_FAILED] = p.count[FLT_VERDICT_FAIL];
    a[FLT_COIL_RULE_NO_BAND] = p.count[FLT_VERDICT_NO_BAND];
    a[FLT_COIL_RULE_NOT_MEASURED] = p.count[FLT_VERDICT_NOT_MEASURED];
    a[FLT_COIL_RULE_NOT_JUDGED] = p.count[FLT_VERDICT_NOT_JUDGED];
    a[FLT_COIL_SHEETS_NOT_JUDGED] = c.not_judged;
    a[FLT_COIL_SHEETS_JUDGED] = c.passed + c.failed;
    a[FLT_COIL_WORST_MIN] = p.min;
    a[FLT_COIL_WORST_MAX] = p.max;
    a[FLT_COIL_WORST_MEAN] = p.measured > 0 ? p.sum / p.measured : k_nan;
    a[FLT_COIL_WORST_SHEET] = p.worst_sheet;
    a[FLT_COIL_WORST_X] = p.worst_x;
    a[FLT_COIL_WORST_S] = p.worst_s;
    for (int h = 0; h < FLT_COIL_HISTOGRAM_BINS; ++h)
        a[FLT_COIL_HISTOGRAM + h] = p.histogram[h];
}

// How many of `lost` frames spread evenly over (prev_s, s) lie in [a, b):
// frame k (1..lost) lies at prev_s + k (s - prev_s) / (lost + 1).
double lost_between(std::uint32_t lost, double prev_s, double s, double a, double b) {
    if (lost == 0)
        return 0.0;
    const double step = (s - prev_s) / (double(lost) + 1.0);
    if (!(step > 0.0))
        return 0.0;
    const double first = std::max(1.0, std::ceil((a - prev_s) / step));
    const double last = std::min(double(lost), std::ceil((b - prev_s) / step) - 1.0);
    return std::max(0.0, last - first + 1.0);
}

}  // namespace

void gauge::evaluate(const sheet_job &job) {
    const stage_timer timer(ns_evaluate_);
    {
        std::lock_guard<std::mutex> lock(m_);
        ++(job.provisional ? n_provisional_ : n_sheets_);
    }
    flt_sheet *sh = take_slot(job.rows);
    if (sh == nullptr)
        return;
    const sheet_buffer &b = buffers_[job.buffer];
    const std::size_t n = job.rows;
    double *v = sh->value;
    std::fill(v, v + k_sheet_values, 0.0);
    v[FLT_SHEET_ID] = double(job.id);
    v[FLT_SHEET_COIL] = double(job.coil);
    v[FLT_SHEET_INDEX] = double(job.index);
    v[FLT_SHEET_S_START] = job.s_start;
    v[FLT_SHEET_S_END] = job.s_end;
    v[FLT_SHEET_ROWS] = double(n);
    v[FLT_SHEET_LOOKAHEAD] = job.lookahead;
    v[FLT_SHEET_LATENCY] = job.latency_s;
    v[FLT_SHEET_CUT_TIME] = 1e-9 * double(job.cut_time_ns);
    v[FLT_SHEET_FIBERS] = double(K_);
    v[FLT_SHEET_ZONES] = double(zones_);
    sh->coil = job.coil_info;  // a reference more: no allocation
    sh->notes = job.notes;     // allocates only when there are notes
    // Frames lost before a row lie between it and the frame before, spread
    // evenly: a sheet counts those in [s_start, s_end), its first row's and
    // the next sheet's first row's included.
    double skipped = 0, dropped = 0, missing = 0, saturated = 0, peaks = 0, invalid = 0;
    double measured = 0;
    const auto count_lost = [&](const row_meta &m) {
        dropped += lost_between(m.dropped, m.prev_s, m.s, job.s_start, job.s_end);
        missing += lost_between(m.missing, m.prev_s, m.s, job.s_start, job.s_end);
    };
    for (std::size_t r = 0; r < n; ++r) {
        const row_meta &m = b.meta[r];
        skipped += m.skipped;
        saturated += m.saturated;
        peaks += m.peaks;
        invalid += m.invalid;
        measured += m.measured ? 1 : 0;
        count_lost(m);
    }
    if (job.has_after)
        count_lost(job.after);
    const double lost_lines = double(n) - measured;
    const double expected = double(n) + dropped + missing;
    const double coverage = expected > 0 ? measured / expected : 0.0;
    v[FLT_SHEET_FRAMES] = double(n);
    v[FLT_SHEET_SKIPPED] = skipped;
    v[FLT_SHEET_DROPPED] = dropped;
    v[FLT_SHEET_SATURATED] = saturated;
    v[FLT_SHEET_PEAKS] = peaks;
    v[FLT_SHEET_INVALID] = invalid;
    v[FLT_SHEET_MISSING] = missing;
    v[FLT_SHEET_LOST_LINES] = lost_lines;
    v[FLT_SHEET_ROWS_MEASURED] = measured;
    v[FLT_SHEET_ROWS_EXPECTED] = expected;
    v[FLT_SHEET_COVERAGE] = coverage;
    unsigned flags = job.flags;
    v[FLT_SHEET_S_FIRST] = n ? b.s[0] : k_nan;
    v[FLT_SHEET_S_LAST] = n ? b.s[n - 1] : k_nan;
    if (n == 0)
        flags |= FLT_SHEET_FLAG_EMPTY;
    if (dropped + missing + lost_lines > 0)
        flags |= FLT_SHEET_FLAG_LOST_ROWS;
    // (a NaN-safe comparison: a sheet expected to hold nothing is incomplete)
    const bool incomplete = !(coverage >= cfg_.min_coverage) || n == 0;
    if (incomplete)
        flags |= FLT_SHEET_FLAG_INCOMPLETE;
    if (!job.provisional) {
        // (an early answer's rows are counted with its final sheet)
        std::lock_guard<std::mutex> lock(m_);
        n_missing_ += std::uint64_t(missing);
        n_lost_lines_ += std::uint64_t(lost_lines);
        n_incomplete_ += incomplete ? 1 : 0;
    }
    const auto id = (unsigned long long)job.id, coil = (unsigned long long)job.coil;
    if (job.provisional)
        FLT_LOG(FLT_LOG_DEBUG, "gauge",
                "sheet %llu (coil %llu): provisional result %.0f mm past its cut", id, coil,
                job.lookahead);
    else if (dropped + missing + lost_lines > 0)
        FLT_LOG(FLT_LOG_WARNING, "gauge",
                "sheet %llu (coil %llu) lost rows: %.0f dropped at a full queue, %.0f missing by "
                "the encoder, %.0f lost lines; %.0f of %.0f rows measured (coverage %.1f %%)",
                id, coil, dropped, missing, lost_lines, measured, expected, 100.0 * coverage);
    if (incomplete && !job.provisional)
        FLT_LOG(FLT_LOG_WARNING, "gauge",
                "sheet %llu (coil %llu) is incomplete: coverage %.1f %% is below "
                "gauge_min_coverage %.1f %%; its shape and verdict are \"not judged\"",
                id, coil, 100.0 * coverage, 100.0 * cfg_.min_coverage);
    if (!job.provisional && peaks > 0 && saturated > cfg_.saturation_limit * peaks)
        FLT_LOG(FLT_LOG_WARNING, "gauge",
                "sheet %llu (coil %llu): %.1f %% of the laser peaks on the strip are saturated "
                "(gauge_saturation_limit %.1f %%): lower the exposure or the laser power",
                id, coil, 100.0 * saturated / peaks, 100.0 * cfg_.saturation_limit);

    // The flatness of the rows: whole sheets through evaluate (which
    // refuses a sheet shorter than one wave or without a valid fiber), short
    // ones through the streamed finish (which reports them flagged).
    flt_flatness *f = nullptr;
    if (n >= 2 && b.s[n - 1] - b.s[0] >= min_length_) {
        const flt_status st = flt_flatness_evaluate_strip(
            flat_, n, K_, b.s.data(), b.z.data(), b.flags.data(), b.left.data(), b.right.data());
        if (st == FLT_OK)
            f = flat_;
        else if (st != FLT_ERR_INVALID_ARGUMENT)
            check(st);
        clear_error();
    } else if (n >= 2) {
        check(flt_flatness_reset(flat_short_));
        std::size_t used = 0;
        int evaluated = 0;
        check(flt_flatness_push_strip(flat_short_, n, K_, b.s.data(), b.z.data(), b.flags.data(),
                                      b.left.data(), b.right.data(), &used, &evaluated));
        check(flt_flatness_finish(flat_short_, &evaluated));
        if (used != n || !evaluated)
            throw error(FLT_ERR_INTERNAL, "a short sheet was not evaluated whole");
        f = flat_short_;
    }
    double *fx = sh->array[FLT_SHEET_FIBER_X].data();
    double *fiu = sh->array[FLT_SHEET_FIBER_I_UNITS].data();
    double *farc = sh->array[FLT_SHEET_FIBER_ARC_LENGTH].data();
    double *fwh = sh->array[FLT_SHEET_FIBER_WAVE_HEIGHT].data();
    double *fwp = sh->array[FLT_SHEET_FIBER_WAVE_PERIOD].data();
    double *fst = sh->array[FLT_SHEET_FIBER_STEEPNESS].data();
    double *ffl = sh->array[FLT_SHEET_FIBER_FLAGS].data();
    double *zx = sh->array[FLT_SHEET_ZONE_CENTRE_X].data();
    double *ziu = sh->array[FLT_SHEET_ZONE_I_UNITS].data();
    double *zfl = sh->array[FLT_SHEET_ZONE_FLAGS].data();
    double *fsx = sh->array[FLT_SHEET_FIBER_STRIP_X].data();
    double *zsx = sh->array[FLT_SHEET_ZONE_STRIP_X].data();
    std::copy(fiber_x_.begin(), fiber_x_.end(), fx);
    std::copy(zone_x_.begin(), zone_x_.end(), zx);
    unsigned window_flags = 0;
    // The flatness window's results, read in place (null: none).
    const window_result *res = f ? &flatness_result_of(f) : nullptr;
    if (res) {
        const window_result &r = *res;
        window_flags = r.flags;
        std::copy(r.arc_length.begin(), r.arc_length.end(), farc);
        std::copy(r.i_units.begin(), r.i_units.end(), fiu);
        std::copy(r.wave_height.begin(), r.wave_height.end(), fwh);
        std::copy(r.wave_period.begin(), r.wave_period.end(), fwp);
        std::copy(r.steepness.begin(), r.steepness.end(), fst);
        std::copy(r.fiber_flags.begin(), r.fiber_flags.end(), ffl);
        std::copy(r.zone_i_units.begin(), r.zone_i_units.end(), ziu);
        std::copy(r.zone_flags.begin(), r.zone_flags.end(), zfl);
        // Where the results lie: on the strip (from its edges) or, without
        // edges, on the fiber grid; in strip and in sensor coordinates.
        std::copy(r.fiber_strip_x.begin(), r.fiber_strip_x.end(), fsx);
        std::copy(r.fiber_sensor_x.begin(), r.fiber_sensor_x.end(), fx);
        std::copy(r.zone_strip_x.begin(), r.zone_strip_x.end(), zsx);
        std::copy(r.zone_sensor_x.begin(), r.zone_sensor_x.end(), zx);
        const flt_shape shape = r.shape;
        const double confidence = r.confidence, bow = r.bow_mm, crossbow = r.crossbow_mm;
        const unsigned components = r.components;
        // An incomplete sheet gets no class as if it were whole.
        v[FLT_SHEET_SHAPE] = double(incomplete ? FLT_SHAPE_NOT_JUDGED : shape);
        v[FLT_SHEET_CONFIDENCE] = incomplete ? 0.0 : confidence;
        v[FLT_SHEET_COMPONENTS] = incomplete ? 0.0 : double(components);
        v[FLT_SHEET_BOW] = bow;
        v[FLT_SHEET_CROSSBOW] = crossbow;
    } else {
        // No valid fiber, one row, or none: every value NaN and flagged.
        window_flags = FLT_WINDOW_NO_VALID_FIBER | FLT_WINDOW_NO_BOW | FLT_WINDOW_NO_CROSSBOW;
        if (n < 2 || b.s[n - 1] - b.s[0] < min_length_)
            window_flags |= FLT_WINDOW_SHORT;
        for (std::size_t k = 0; k < K_; ++k) {
            fiu[k] = farc[k] = fwh[k] = fwp[k] = fst[k] = fsx[k] = k_nan;
            ffl[k] = double(FLT_FIBER_NO_DATA | FLT_FIBER_NO_WAVE);
        }
        for (std::size_t j = 0; j < zones_; ++j) {
            ziu[j] = zsx[j] = k_nan;
            zfl[j] = double(FLT_ZONE_NO_DATA);
        }
        v[FLT_SHEET_SHAPE] = double(incomplete ? FLT_SHAPE_NOT_JUDGED : FLT_SHAPE_UNDETERMINED);
        v[FLT_SHEET_CONFIDENCE] = 0.0;
        v[FLT_SHEET_COMPONENTS] = 0.0;
        v[FLT_SHEET_BOW] = k_nan;
        v[FLT_SHEET_CROSSBOW] = k_nan;
    }
    v[FLT_SHEET_WINDOW_FLAGS] = double(window_flags);

    // The strip's width and lateral position: from the extractor's edges
    // where the flatness window had them (smoothed along the sheet: mean,
    // min and max over its rows); else the outer fibers with data.
    if (res && (window_flags & FLT_WINDOW_ON_STRIP)) {
        const double *width = res->strip_width, *centre = res->strip_centre;
        v[FLT_SHEET_STRIP_WIDTH] = width[0];
        v[FLT_SHEET_STRIP_WIDTH_MIN] = width[1];
        v[FLT_SHEET_STRIP_WIDTH_MAX] = width[2];
        v[FLT_SHEET_STRIP_CENTRE] = centre[0];
        v[FLT_SHEET_STRIP_CENTRE_MIN] = centre[1];
        v[FLT_SHEET_STRIP_CENTRE_MAX] = centre[2];
        v[FLT_SHEET_STRIP_LEFT] = centre[0] - 0.5 * width[0];
        v[FLT_SHEET_STRIP_RIGHT] = centre[0] + 0.5 * width[0];
    } else {
        long first = -1, last = -1;
        for (std::size_t k = 0; k < K_; ++k)
            if (!(unsigned(ffl[k]) & FLT_FIBER_NO_DATA)) {
                if (first < 0)
                    first = long(k);
                last = long(k);
            }
        if (first >= 0) {
            v[FLT_SHEET_STRIP_LEFT] = fx[first] - 0.5 * pitch_;
            v[FLT_SHEET_STRIP_RIGHT] = fx[last] + 0.5 * pitch_;
        } else {
            flags |= FLT_SHEET_FLAG_NO_EDGES;
            v[FLT_SHEET_STRIP_LEFT] = v[FLT_SHEET_STRIP_RIGHT] = k_nan;
        }
        v[FLT_SHEET_STRIP_WIDTH] = v[FLT_SHEET_STRIP_WIDTH_MIN] = v[FLT_SHEET_STRIP_WIDTH_MAX] =
            v[FLT_SHEET_STRIP_RIGHT] - v[FLT_SHEET_STRIP_LEFT];
        v[FLT_SHEET_STRIP_CENTRE] = v[FLT_SHEET_STRIP_CENTRE_MIN] = v[FLT_SHEET_STRIP_CENTRE_MAX] =
            0.5 * (v[FLT_SHEET_STRIP_LEFT] + v[FLT_SHEET_STRIP_RIGHT]);
    }
    // The largest wave over the fibers.
    long wave = -1;
    for (std::size_t k = 0; k < K_; ++k)
        if (!(unsigned(ffl[k]) & (FLT_FIBER_NO_DATA | FLT_FIBER_NO_WAVE)) &&
            (wave < 0 || fwh[k] > fwh[wave]))
            wave = long(k);
    if (wave >= 0) {
        v[FLT_SHEET_WAVE_HEIGHT] = fwh[wave];
        v[FLT_SHEET_WAVE_PERIOD] = fwp[wave];
        v[FLT_SHEET_WAVE_STEEPNESS] = fst[wave];
        v[FLT_SHEET_WAVE_X] = fx[wave];
    } else {
        flags |= FLT_SHEET_FLAG_NO_WAVE;
        v[FLT_SHEET_WAVE_HEIGHT] = v[FLT_SHEET_WAVE_PERIOD] = k_nan;
        v[FLT_SHEET_WAVE_STEEPNESS] = v[FLT_SHEET_WAVE_X] = k_nan;
    }
    double max_iu = k_nan;
    for (std::size_t j = 0; j < zones_; ++j)
        if (!(unsigned(zfl[j]) & FLT_ZONE_NO_DATA) && !(ziu[j] <= max_iu))
            max_iu = ziu[j];
    v[FLT_SHEET_MAX_I_UNITS] = max_iu;
    v[FLT_SHEET_FLAGS] = double(flags);

    // The verdict, from the sheet buffer's map (kept whatever
    // gauge_keep_maps says) and the values above.
    judge(sh, b, n);
    // Evaluated and judged: the time it is handed out (FINISHED_TIME less
    // CUT_TIME is then the whole wait for a verdict).
    v[FLT_SHEET_FINISHED_TIME] = 1e-9 * double(record::utc_now_ns());

    sh->rows = n;
    if (cfg_.keep_maps >= 1) {
        std::memcpy(sh->map_s.data(), b.s.data(), n * sizeof(double));
        std::memcpy(sh->map_z.data(), b.z.data(), n * K_ * sizeof(double));
        std::memcpy(sh->map_flags.data(), b.flags.data(), n * K_);
    }
    if (cfg_.keep_maps >= 2)
        std::memcpy(sh->map_measured.data(), b.measured.data(), n * K_ * sizeof(double));
    sh->magic = k_sheet_magic;
    // The record keeps final sheets only (the early answer's final follows).
    if (archive_ != nullptr && !job.provisional)
        archive_sheet(*sh, b, n);
    if (recorder_ != nullptr && !job.provisional && recorder_->frames_on_fail() &&
        sh->value[FLT_SHEET_VERDICT] == FLT_VERDICT_FAIL)
        recorder_->save_frames();  // the frames that showed the failure
    deliver(sh);
}

void gauge::judge(flt_sheet *sh, const sheet_buffer &b, std::size_t n) {
    std::shared_ptr<verdict_config> vc;
    {
        std::lock_guard<std::mutex> lock(rules_m_);
        vc = verdict_;  // a reference more: no allocation
    }
    double *v = sh->value;
    sh->verdict = vc;  // may free a replaced rule set (never allocates)
    v[FLT_SHEET_RULES] = 0;
    v[FLT_SHEET_RULES_FAILED] = 0;
    v[FLT_SHEET_VERDICT] = FLT_VERDICT_NOT_JUDGED;  // no rules: nothing judged it
    if (!vc)
        return;
    if (sh->grown && !sh->own_verdict) {
        // A sheet made beyond the slots has no verdict among the slots'.
        auto own = std::make_unique<flt_verdict>();
        own->borrowed = true;
        own->set = vc->rules.set;
        const std::size_t rules = own->set.rules.size();
        own->results.resize(rules);
        own->pending.resize(rules);
        own->gaps.resize(rules);
        sh->own_verdict = std::move(own);
    }
    flt_verdict &vd = sh->own_verdict ? *sh->own_verdict : *vc->slot[sh->slot];
    // The flatness measures and where they are: s the sheet's middle; x
    // the largest zone's centre, the largest wave's fiber, the strip's
    // centre for bow and crossbow (the sensor's centre without edges).
    const double s_mid = n ? 0.5 * (b.s[0] + b.s[n - 1]) : k_nan;
    const double x_centre = std::isnan(v[FLT_SHEET_STRIP_CENTRE])
                                ? 0.5 * (fiber_x_.front() + fiber_x_.back())
                                : v[FLT_SHEET_STRIP_CENTRE];
    const auto give = [&](flt_measure m, double value, double x) {
        verdict::given_measure &g = vd.given[m];
        g = verdict::given_measure{};
        if (!std::isnan(value) && !std::isnan(x) && !std::isnan(s_mid)) {
            g.value = value;
            g.x = x;
            g.s = s_mid;
        }
    };
    const double *ziu = sh->array[FLT_SHEET_ZONE_I_UNITS].data();
    const double *zfl = sh->array[FLT_SHEET_ZONE_FLAGS].data();
    const double *zx = sh->array[FLT_SHEET_ZONE_CENTRE_X].data();
    long zone = -1;
    for (std::size_t j = 0; j < zones_; ++j)
        if (!(unsigned(zfl[j]) & FLT_ZONE_NO_DATA) && (zone < 0 || ziu[j] > ziu[zone]))
            zone = long(j);
    give(FLT_MEASURE_ZONE_I_UNITS, zone >= 0 ? ziu[zone] : k_nan, zone >= 0 ? zx[zone] : k_nan);
    give(FLT_MEASURE_WAVE_STEEPNESS, v[FLT_SHEET_WAVE_STEEPNESS], v[FLT_SHEET_WAVE_X]);
    give(FLT_MEASURE_WAVE_HEIGHT, v[FLT_SHEET_WAVE_HEIGHT], v[FLT_SHEET_WAVE_X]);
    give(FLT_MEASURE_BOW, v[FLT_SHEET_BOW], x_centre);
    give(FLT_MEASURE_CROSSBOW, v[FLT_SHEET_CROSSBOW], x_centre);
    // The coil's nominal thickness and width, where given, choose the bands.
    const double thickness =
        sh->coil && sh->coil->thickness_mm > 0 ? sh->coil->thickness_mm : vc->thickness;
    const double width = sh->coil && sh->coil->width_mm > 0 ? sh->coil->width_mm
                         : vc->width > 0                    ? vc->width
                                                            : v[FLT_SHEET_STRIP_WIDTH];
    verdict::map_view map;
    if (n > 0 && vc->needs_map) {
        map.rows = n;
        map.fibers = K_;
        map.s = b.s.data();
        map.x = fiber_x_.data();
        map.z = b.z.data();
        map.flags = b.flags.data();
    }
    if (unsigned(v[FLT_SHEET_FLAGS]) & FLT_SHEET_FLAG_INCOMPLETE) {
        // Not judged: an incomplete sheet's measures are those of the rows
        // it has, not the sheet's. Each rule says which band would apply.
        for (std::size_t i = 0; i < vd.results.size(); ++i) {
            const verdict::rule &r = vd.set.rules[i];
            double *out = vd.results[i].value;
            std::fill(out, out + verdict::k_values, k_nan);
            out[FLT_VERDICT_STATE] = FLT_VERDICT_NOT_JUDGED;
            out[FLT_VERDICT_MEASURE] = double(r.measure);
            out[FLT_VERDICT_LENGTH] = r.length;
            const int band = width > 0 ? r.band_of(thickness, width) : -1;
            out[FLT_VERDICT_BAND] = band;
            if (band >= 0)
                out[FLT_VERDICT_LIMIT] = r.bands[std::size_t(band)].limit;
        }
    } else {
        // Each straightedge rule's lines in blocks on the workers.
        verdict::judge(vd.set, vd.given, vc->workspace, blocks_, thickness, width, map,
                       vd.results.data(), vd.gaps.data());
    }
    const bool provisional = unsigned(v[FLT_SHEET_FLAGS]) & FLT_SHEET_FLAG_PROVISIONAL;
    if (!(unsigned(v[FLT_SHEET_FLAGS]) & FLT_SHEET_FLAG_INCOMPLETE) && !provisional) {
        // A band that changes within a coil (a measured width crossing a
        // band's edge) changes the limit: worth telling.
        const double coil = v[FLT_SHEET_COIL];
        for (std::size_t i = 0; i < vd.results.size() && i < vc->last_band.size(); ++i) {
            const int band = int(vd.results[i].value[FLT_VERDICT_BAND]);
            if (vc->last_coil == coil && band != vc->last_band[i])
                FLT_LOG(FLT_LOG_INFO, "gauge",
                        "sheet %.0f: rule '%s' is judged by band %d, was %d (thickness %g mm, "
                        "width %.0f mm)",
                        v[FLT_SHEET_ID], vd.set.rules[i].name.c_str(), band, vc->last_band[i],
                        thickness, width);
            vc->last_band[i] = band;
        }
        vc->last_coil = coil;
    }
    vd.evaluated = true;
    double failed = 0, unjudged = 0;
    for (const verdict::rule_result &r : vd.results) {
        const double state = r.value[FLT_VERDICT_STATE];
        failed += state == FLT_VERDICT_FAIL ? 1 : 0;
        unjudged += state != FLT_VERDICT_FAIL && state != FLT_VERDICT_PASS ? 1 : 0;
    }
    v[FLT_SHEET_RULES] = double(vd.results.size());
    v[FLT_SHEET_RULES_FAILED] = failed;
    // A failure is certain whatever else could not be judged; a pass needs
    // every rule judged.
    v[FLT_SHEET_VERDICT] = failed > 0                           ? FLT_VERDICT_FAIL
                           : unjudged > 0 || vd.results.empty() ? FLT_VERDICT_NOT_JUDGED
                                                                : FLT_VERDICT_PASS;
    if (!provisional)  // the coil's statistics count final verdicts only
        count_in_coil(*vc, *sh);
}

void coil_stats::reset(std::uint64_t gen, std::size_t n_rules) {
    generation = gen;
    coil = sheets = passed = failed = not_judged = 0;
    finished = false;
    coil_info.reset();
    per_rule zero{};
    zero.min = zero.max = zero.worst_sheet = zero.worst_x = zero.worst_s = k_nan;
    rules.assign(n_rules, zero);  // within the capacity set_rules reserved
}

void gauge::count_in_coil(const verdict_config &vc, const flt_sheet &sh) {
    const flt_verdict &vd = sh.own_verdict ? *sh.own_verdict : *vc.slot[sh.slot];
    const double *v = sh.value;
    std::lock_guard<std::mutex> lock(stats_m_);
    coil_stats &c = coil_current_;
    if (c.generation != vc.generation)
        return;  // judged by rules replaced since (their statistics restarted)
    const double coil = v[FLT_SHEET_COIL];
    const auto finish = [&] {
        c.finished = true;
        std::swap(coil_last_, coil_current_);  // moves: no allocation
        coil_current_.reset(coil_last_.generation, coil_last_.rules.size());
    };
    if (c.sheets > 0 && c.coil != coil)
        finish();  // the previous coil's last sheet was not judged (lost)
    c.coil = coil;
    c.sheets += 1;
    if (c.sheets == 1)
        c.coil_info = sh.coil;  // a reference more: no allocation
    // By the sheet's verdict: a sheet no rule could judge is not passed.
    const double verdict = v[FLT_SHEET_VERDICT];
    (verdict == FLT_VERDICT_FAIL   ? c.failed
     : verdict == FLT_VERDICT_PASS ? c.passed
                                   : c.not_judged) += 1;
    for (std::size_t i = 0; i < c.rules.size() && i < vd.results.size(); ++i) {
        const double *r = vd.results[i].value;
        coil_stats::per_rule &p = c.rules[i];
        const int state = int(r[FLT_VERDICT_STATE]);
        if (state >= 0 && state < 5)
            p.count[state] += 1;
        if (state != FLT_VERDICT_PASS && state != FLT_VERDICT_FAIL)
            continue;
        const double worst = r[FLT_VERDICT_WORST];
        p.measured += 1;
        p.sum += worst;
        if (!(worst >= p.min))
            p.min = worst;
        if (!(worst <= p.max)) {
            p.max = worst;
            p.worst_sheet = v[FLT_SHEET_ID];
            p.worst_x = r[FLT_VERDICT_X];
            p.worst_s = r[FLT_VERDICT_S];
        }
        // Bin i holds worst / limit in (i / 10, (i + 1) / 10]: passes in
        // 0-9, failures in 10-19 whatever the rounding of the ratio.
        const double ratio = worst / r[FLT_VERDICT_LIMIT];
        long bin = long(std::ceil(std::min(ratio, 100.0) * 10.0)) - 1;
        bin = std::max(0L, std::min(long(FLT_COIL_HISTOGRAM_BINS) - 1, bin));
        if (state == FLT_VERDICT_PASS)
            bin = std::min(bin, 9L);
        else
            bin = std::max(bin, 10L);
        p.histogram[bin] += 1;
    }
    const unsigned flags = unsigned(v[FLT_SHEET_FLAGS]);
    if (flags & (FLT_SHEET_FLAG_TAIL | FLT_SHEET_FLAG_NEW_STRIP | FLT_SHEET_FLAG_FLUSHED))
        finish();
}

flt_status gauge::set_rules(const char *fn, const flt_rules *rules, double thickness,
                            double width) {
    std::shared_ptr<verdict_config> vc;
    std::size_t n = 0;
    if (rules) {
        vc = std::make_shared<verdict_config>();
        vc->rules.set = rules->set;
        vc->rules.borrowed = true;
        vc->thickness = thickness;
        vc->width = width;
        vc->needs_map = verdict::needs_map(rules->set);
        n = rules->set.rules.size();
        vc->last_band.assign(n, -1);
        vc->slot.resize(cfg_.sheet_slots);
        for (std::unique_ptr<flt_verdict> &vd : vc->slot) {
            vd = std::make_unique<flt_verdict>();
            vd->borrowed = true;
            vd->set = rules->set;
            vd->results.resize(n);
            vd->pending.resize(n);
            vd->gaps.resize(n);
        }
        // The straightedge over the longest line it will meet: a fiber of
        // the longest sheet, or a row of every fiber.
        if (vc->needs_map) {
            // A scratch per participant of the evaluation's blocks, each
            // for the longest line; room for the most blocks of every rule.
            vc->workspace.reserve(n, std::max(sheet_capacity_, K_), blocks_.participants());
        }
    }
    {
        std::lock_guard<std::mutex> stats_lock(stats_m_);
        coil_current_.rules.reserve(n);
        coil_last_.rules.reserve(n);
        std::lock_guard<std::mutex> lock(rules_m_);
        const std::uint64_t gen = vc ? ++rules_generation_ : 0;
        if (vc)
            vc->generation = gen;
        verdict_.swap(vc);
        coil_current_.reset(gen, n);
    }
    (void)fn;
    return FLT_OK;  // the replaced rules (vc) are freed here, unless a sheet holds them
}

flt_status gauge::coil_stats_of(const char *fn, flt_coil which, std::size_t rule, std::size_t count,
                                double *out) const {
    std::lock_guard<std::mutex> lock(stats_m_);
    const coil_stats &c = which == FLT_COIL_LAST ? coil_last_ : coil_current_;
    if (c.generation == 0)
        return fail(FLT_ERR_STATE,
                    which == FLT_COIL_LAST
                        ? "%s: no coil has finished under rules yet (flt_gauge_set_rules)"
                        : "%s: the gauge has no rules (flt_gauge_set_rules)",
                    fn);
    if (rule >= c.rules.size())
        return fail(FLT_ERR_NOT_FOUND, "%s: argument 'rule' = %zu is past the last of %zu rules",
                    fn, rule, c.rules.size());
    const coil_stats::per_rule &p = c.rules[rule];
    double all[FLT_COIL_VALUES];
    coil_rule_values(c, p, all);
    std::copy(all, all + count, out);
    return FLT_OK;
}

void gauge::deliver(flt_sheet *sheet) {
    std::lock_guard<std::mutex> dl(deliver_m_);
    if (callback_) {
        sheet->borrowed = true;
        t_in_callback = this;
        callback_(sheet, callback_user_);
        t_in_callback = nullptr;
        pool_->give_back(sheet);
        return;
    }
    std::lock_guard<std::mutex> lock(m_);
    if (ready_count_ == ready_.size()) {
        // More sheets wait than there are slots (they were made beyond
        // them): a longer ring, in order.
        std::vector<flt_sheet *> longer(2 * ready_.size(), nullptr);
        for (std::size_t i = 0; i < ready_count_; ++i)
            longer[i] = ready_[(ready_head_ + i) % ready_.size()];
        ready_.swap(longer);
        ready_head_ = 0;
    }
    ready_[(ready_head_ + ready_count_) % ready_.size()] = sheet;
    ++ready_count_;
    sheet_cv_.notify_all();
}

std::unique_ptr<record::sheet_record>
archive_record_of(const flt_sheet &sh, const record::archive &ar, const std::string &session,
                  std::size_t rows, const double *s, const double *z, const std::uint8_t *flags);

void gauge::archive_sheet(const flt_sheet &sh, const sheet_buffer &b, std::size_t n) {
    std::unique_ptr<record::sheet_record> r =
        archive_record_of(sh, *archive_, pool_->session, n, b.s.data(), b.z.data(), b.flags.data());
    const unsigned flags = unsigned(sh.value[FLT_SHEET_FLAGS]);
    if (flags & (FLT_SHEET_FLAG_TAIL | FLT_SHEET_FLAG_NEW_STRIP | FLT_SHEET_FLAG_FLUSHED)) {
        // The coil's last sheet: its statistics go with it.
        r->ends_coil = true;
        std::lock_guard<std::mutex> lock(stats_m_);
        const coil_stats &c = coil_last_;
        if (c.generation != 0 && c.coil == sh.value[FLT_SHEET_COIL] && sh.verdict) {
            for (std::size_t i = 0; i < c.rules.size(); ++i) {
                record::coil_rule_stats st;
                const char *name = "";
                if (flt_rules_rule(&sh.verdict->rules, i, &name, nullptr, nullptr) == FLT_OK)
                    st.name = name;
                st.values.resize(FLT_COIL_VALUES);
                const coil_stats::per_rule &p = c.rules[i];
                coil_rule_values(c, p, st.values.data());
                r->coil_stats.push_back(std::move(st));
            }
            clear_error();
        }
    }
    if (!archive_->add(std::move(r)))
        FLT_LOG(FLT_LOG_ERROR, "archive",
                "sheet %.0f (coil %.0f) is not archived: archive_buffer_mb is full of sheets the "
                "database has not taken (%s)",
                sh.value[FLT_SHEET_ID], sh.value[FLT_SHEET_COIL], archive_->last_error().c_str());
}

}  // namespace flt
