//! Getting and setting values by value reference: type checks, range and
//! limit checks, and tunable parameters reaching the running simulation.

use super::{Engine, Slave, SpectrumCache};
use crate::chassis_outputs::ChassisOutputId;
use crate::error::{FmiError, Status};
use crate::guards;
use crate::outputs::OutputId;
use crate::phase::Phase;
use crate::variables::{
    Access, Calculated, Causality, Dimension, FmiVersion, VarType, Variability, Variable, by_name,
    by_vr,
};
use tdvass::analysis::spectrum::CharacteristicRootSolver;
use tdvass::model::Variant;
use tdvass::model::inputs::{BODY_ATTACHMENT, prescribed_by_name};
use tdvass::solver::{Instantaneous, Outputs, TimeAverages};

/// What one getter call has computed of the outputs so far: each part at
/// most once per call.
#[derive(Default)]
struct OutputRead {
    /// The call asks for an output that only all outputs give: they are
    /// computed for every output it asks for (at less cost than a part
    /// first and all of them after).
    all_needed: bool,
    /// Every output.
    outputs: Option<Outputs>,
    /// The time averages alone.
    averages: Option<TimeAverages>,
    /// The instantaneous outputs alone.
    instant: Option<Instantaneous>,
}

/// The value references of the last `GetReal` call whose every reference
/// is a Real variable (at most [`ReadPlan::CAPACITY`] of them), their
/// variables, and whether they ask for an output that only all outputs
/// give: a master asks for the same list at every communication point, so
/// the list is looked up once.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ReadPlan {
    vrs: [u32; ReadPlan::CAPACITY],
    variables: [Option<&'static Variable>; ReadPlan::CAPACITY],
    len: usize,
    all_needed: bool,
}

impl ReadPlan {
    /// The longest list kept.
    const CAPACITY: usize = 32;
}

impl Slave {
    /// The plan of a `GetReal` of `vrs`: the kept one when the list is the
    /// same, else a new one (kept), or `None` when a reference is not a
    /// Real variable or the list is longer than a plan holds (the caller
    /// then looks each reference up, with its error).
    fn read_plan(&mut self, vrs: &[u32]) -> Option<ReadPlan> {
        let kept = &self.read_plan;
        if kept.vrs.get(..kept.len) == Some(vrs) {
            return Some(*kept);
        }
        if vrs.len() > ReadPlan::CAPACITY {
            return None;
        }
        let mut plan = ReadPlan {
            len: vrs.len(),
            ..ReadPlan::default()
        };
        for (i, &vr) in vrs.iter().enumerate() {
            let var = self.variable(vr, VarType::Real).ok()?;
            plan.vrs[i] = vr;
            plan.variables[i] = Some(var);
            plan.all_needed |= matches!(var.access, Access::Output(id)
                if !id.is_time_average() && !id.is_instantaneous());
        }
        self.read_plan = plan;
        Some(plan)
    }

    pub(super) fn variable(&self, vr: u32, ty: VarType) -> Result<&'static Variable, FmiError> {
        let var = by_vr(self.model(), self.dialect.version, vr).ok_or_else(|| {
            FmiError::error(format!(
                "unknown value reference {vr} (for a {})",
                ty.as_str()
            ))
        })?;
        if var.var_type() != ty {
            return Err(FmiError::error(format!(
                "value reference {vr} is `{}`, a {}, not a {}",
                var.name,
                var.var_type().as_str(),
                ty.as_str()
            )));
        }
        Ok(var)
    }

    /// The outputs now: from the simulation, or during initialization from
    /// a simulator built from the current settings.
    /// A non-finite output is never handed out (a last line of defence:
    /// the states are bounded at every step).
    fn outputs(&mut self) -> Result<Outputs, FmiError> {
        let outputs = match &mut self.state.engine {
            Engine::ModelExchange(Some(model)) => model.outputs(),
            Engine::CoSimulation(Some(sim)) => sim.outputs(),
            _ => self.build_simulator()?.outputs(),
        };
        match guards::non_finite_output(self.model(), &outputs) {
            None => Ok(outputs),
            Some((name, value)) => Err(FmiError::error(format!(
                "output `{name}` = {value} is not finite at t = {} s",
                outputs.time
            ))),
        }
    }

    /// The time averages among the outputs now ([`Self::outputs`] has
    /// them too, at more cost).
    fn time_averages(&mut self) -> Result<TimeAverages, FmiError> {
        if self.state.engine.exchange().is_some() {
            return Ok(self.outputs()?.time_averages());
        }
        Ok(match self.state.engine.simulator_mut() {
            Some(sim) => sim.time_averages(),
            None => self.build_simulator()?.time_averages(),
        })
    }

    /// The instantaneous outputs now ([`Self::outputs`] has them too, at
    /// more cost).
    fn instantaneous(&mut self) -> Result<Instantaneous, FmiError> {
        if self.state.engine.exchange().is_some() {
            let o = self.outputs()?;
            return Ok(Instantaneous {
                time: o.time,
                state: o.state,
                performance: o.performance,
                road_displacement: o.road_displacement,
                control_force: o.control_force,
                body_force: o.body_force,
                dynamic_tire_load: o.dynamic_tire_load,
            });
        }
        Ok(match self.state.engine.simulator_mut() {
            Some(sim) => sim.instantaneous(),
            None => self.build_simulator()?.instantaneous(),
        })
    }

    /// The chassis's output `id` now: of the running chassis, or during
    /// initialization of one built from the current settings.
    fn chassis_output(&self, id: ChassisOutputId) -> Result<f64, FmiError> {
        if let Some(chassis) = self.state.engine.chassis() {
            return Ok(id.value(chassis));
        }
        Ok(id.value(&self.build_chassis()?))
    }

    /// The value of output `id` now. The outputs of one getter call are
    /// computed once (`read.outputs`); a call that asks only for time
    /// averages, or only for instantaneous outputs, computes those alone
    /// (`read.averages`, `read.instant`).
    fn output_value(&mut self, id: OutputId, read: &mut OutputRead) -> Result<f64, FmiError> {
        if read.outputs.is_none() && !read.all_needed {
            let quick = if id.is_time_average() {
                let averages = match read.averages {
                    Some(a) => a,
                    None => *read.averages.insert(self.time_averages()?),
                };
                id.time_average(&averages)
            } else if id.is_instantaneous() {
                let instant = match read.instant {
                    Some(i) => i,
                    None => *read.instant.insert(self.instantaneous()?),
                };
                id.instantaneous(&instant)
            } else {
                None
            };
            // A value that is not finite takes the full path, whose check
            // reports it (`guards::non_finite_output`).
            if let Some(value) = quick.filter(|v| v.is_finite()) {
                return Ok(value);
            }
        }
        let outputs = match &mut read.outputs {
            Some(o) => o,
            None => read.outputs.insert(self.outputs()?),
        };
        Ok(id.value(outputs))
    }

    /// The spectral abscissa at the current settings (cached).
    pub fn spectral_abscissa(&mut self) -> Result<f64, FmiError> {
        let params = self.state.settings.params();
        let variant = self.state.settings.variant;
        let fresh = self
            .spectrum
            .as_ref()
            .is_some_and(|c| c.params == params && c.variant == variant);
        if !fresh {
            let value = Variant::from_code(variant as i64)
                .and_then(|v| tdvass::analysis::spectrum::spectral_abscissa(&params, v))
                .map_err(|e| e.to_string());
            self.spectrum = Some(SpectrumCache {
                params,
                variant,
                value,
            });
        }
        match &self.spectrum {
            Some(SpectrumCache { value: Ok(a), .. }) => Ok(*a),
            Some(SpectrumCache { value: Err(e), .. }) => Err(FmiError::error(format!(
                "spectral abscissa not available: {e}"
            ))),
            None => unreachable!("filled above"),
        }
    }

    /// How many values `var` holds: 1 for a scalar, the product of its
    /// dimensions for an array.
    pub fn size_of(&self, var: &Variable) -> usize {
        var.dimensions
            .iter()
            .map(|d| match d {
                Dimension::Fixed(n) => *n as usize,
                Dimension::Structural(name) => match by_name(self.model(), FmiVersion::Fmi3, name)
                    .map(|v| v.access)
                {
                    Some(Access::Integer { get, .. }) => get(&self.state.settings).max(0) as usize,
                    _ => 0,
                },
            })
            .product()
    }

    /// The `root_count` rightmost characteristic roots at the current
    /// settings, `(re, im)` each, rightmost first.
    fn rightmost_roots(&self) -> Result<Vec<f64>, FmiError> {
        let settings = &self.state.settings;
        let count = settings.root_count.max(0) as usize;
        let variant = Variant::from_code(settings.variant as i64)?;
        let tau = if variant.has_control() {
            settings.params.tau
        } else {
            0.0
        };
        let roots = CharacteristicRootSolver::new(&settings.params, variant)
            .and_then(|solver| solver.rightmost_roots(tau, count))
            .map_err(|e| FmiError::error(format!("rightmost roots not available: {e}")))?;
        if roots.len() < count {
            return Err(FmiError::error(format!(
                "`root_count` = {count} asks for more roots than were found ({}; CS has 4, PVASS 6)",
                roots.len()
            )));
        }
        Ok(roots.iter().flat_map(|r| [r.re, r.im]).collect())
    }

    /// `GetReal` / `GetFloat64`: scalars one value each, arrays their
    /// elements in row-major order; `values` must hold exactly as many as
    /// the value references need.
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<Status, FmiError> {
        let plan = self.read_plan(vrs);
        let mut read = OutputRead {
            // Without a plan (a list longer than a plan holds, or one with
            // a reference that is not a Real variable, refused below) the
            // outputs are read from all outputs.
            all_needed: plan.as_ref().is_none_or(|p| p.all_needed),
            ..OutputRead::default()
        };
        let mut at = 0;
        for (i, &vr) in vrs.iter().enumerate() {
            let var = match plan.as_ref().and_then(|p| p.variables[i]) {
                Some(var) => var,
                None => self.variable(vr, VarType::Real)?,
            };
            let size = self.size_of(var);
            let available = values.len();
            let Some(slots) = values.get_mut(at..at + size) else {
                return Err(FmiError::error(format!(
                    "{available} values given for value references that hold more (`{}` needs {size} from position {at})",
                    var.name
                )));
            };
            match var.access {
                Access::Real { get, .. } => slots[0] = get(&self.state.settings),
                Access::Time => slots[0] = self.time(),
                Access::Output(id) => slots[0] = self.output_value(id, &mut read)?,
                Access::ChassisOutput(id) => slots[0] = self.chassis_output(id)?,
                Access::ContinuousState(i) => slots[0] = self.continuous_states()?[i],
                Access::StateDerivative(i) => slots[0] = self.state_derivatives()?[i],
                Access::EventIndicator(i) => slots[0] = self.event_indicator_values()?[i],
                Access::Calculated(Calculated::SpectralAbscissa) => {
                    slots[0] = self.spectral_abscissa()?
                }
                Access::Calculated(Calculated::RightmostRoots) => {
                    slots.copy_from_slice(&self.rightmost_roots()?)
                }
                Access::Integer { .. }
                | Access::IntegerOutput(_)
                | Access::Calculated(Calculated::Stable) => {
                    unreachable!("type checked")
                }
            }
            if let Some(value) = slots.iter_mut().find(|v| !v.is_finite()) {
                let bad = std::mem::replace(value, 0.0);
                return Err(FmiError::error(format!(
                    "`{}` = {bad} is not finite; no value returned",
                    var.name
                )));
            }
            at += size;
        }
        if at != values.len() {
            return Err(FmiError::error(format!(
                "{} values given, the value references hold {at}",
                values.len()
            )));
        }
        Ok(Status::Ok)
    }

    /// `GetInteger`: the Integer settings and the counts.
    pub fn get_integer(&mut self, vrs: &[u32], values: &mut [i32]) -> Result<Status, FmiError> {
        let mut outputs = None;
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            let var = self.variable(vr, VarType::Integer)?;
            match var.access {
                Access::Integer { get, .. } => *value = get(&self.state.settings),
                Access::IntegerOutput(id) => {
                    if outputs.is_none() {
                        outputs = Some(self.outputs()?);
                    }
                    *value = id
                        .value(outputs.as_ref().expect("computed above"))
                        .ok_or_else(|| {
                            FmiError::error(format!("`{}` is not available", var.name))
                        })?;
                }
                _ => unreachable!("type checked"),
            }
        }
        Ok(Status::Ok)
    }

    /// `GetBoolean`.
    pub fn get_boolean(&mut self, vrs: &[u32], values: &mut [bool]) -> Result<Status, FmiError> {
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            match self.variable(vr, VarType::Boolean)?.access {
                Access::Calculated(Calculated::Stable) => *value = self.spectral_abscissa()? < 0.0,
                _ => unreachable!("type checked"),
            }
        }
        Ok(Status::Ok)
    }

    /// `GetString`: there are no String variables, so any value
    /// reference is refused.
    pub fn get_string(&mut self, vrs: &[u32]) -> Result<Status, FmiError> {
        for &vr in vrs {
            self.variable(vr, VarType::String)?;
        }
        Ok(Status::Ok)
    }

    /// Whether `var` may be set now to `value` (the state table already
    /// allows setting something).
    fn check_settable(&self, var: &Variable, value: f64) -> Result<(), FmiError> {
        match (var.causality, var.variability) {
            (Causality::Output, _) => Err(FmiError::error(format!(
                "`{}` is an output and cannot be set (value {value} refused)",
                var.name
            ))),
            (Causality::Local, _) => Err(FmiError::error(format!(
                "`{}` is a continuous state or derivative: a Model Exchange master sets the states with SetContinuousStates (value {value} refused)",
                var.name
            ))),
            (Causality::CalculatedParameter, _) => Err(FmiError::error(format!(
                "`{}` is a calculated parameter and cannot be set (value {value} refused)",
                var.name
            ))),
            (Causality::Independent, _) => Err(FmiError::error(format!(
                "`{}` is the independent variable and cannot be set (value {value} refused)",
                var.name
            ))),
            (Causality::Parameter, _) if self.state.phase == Phase::ContinuousTimeMode => {
                Err(FmiError::error(format!(
                    "`{}` is a parameter: in Model Exchange it can be changed in Event Mode only, not in Continuous-Time Mode (value {value} refused)",
                    var.name
                )))
            }
            (Causality::StructuralParameter, _) if self.state.phase != Phase::Instantiated => {
                Err(FmiError::error(format!(
                    "`{}` is a structural parameter: it can be set only before initialization (value {value} refused; reset the instance to change it)",
                    var.name
                )))
            }
            (Causality::Parameter, Variability::Fixed) if self.state.phase.is_simulating() => {
                Err(FmiError::error(format!(
                    "`{}` is a fixed parameter and cannot be changed after initialization (value {value} refused; reset the instance to change it)",
                    var.name
                )))
            }
            _ => {
                var.range.check(var.name, value)?;
                guards::check_variable(var, value)
            }
        }
    }

    /// Applies a checked Real value; tunable parameters reach the running
    /// simulation at once.
    fn apply_real(&mut self, var: &Variable, value: f64) -> Result<(), FmiError> {
        let Access::Real { set, .. } = var.access else {
            unreachable!("only settable Reals get here")
        };
        set(&mut self.state.settings, value);
        if let Some(i) = super::stepping::force_index(var.name) {
            // A force set anew holds from now on unless its derivative is
            // given again; the running chassis takes it at once (its
            // accelerations depend on it directly).
            self.state.settings.force_rates[i] = 0.0;
            self.force_set(i, false);
            if let Some(chassis) = self.state.engine.chassis_mut() {
                let (mut forces, mut rates) = chassis.forces();
                forces[i] = value;
                rates[i] = 0.0;
                chassis.set_forces(forces, rates)?;
            }
        }
        let weights = self.state.settings.weights();
        match (var.name, self.state.engine.simulator_mut()) {
            ("x_g", _) => {
                self.state.input_slope = 0.0;
                self.state.input_slope_given = false;
                self.state.input_pending = true;
            }
            ("g", Some(sim)) => {
                sim.set_gain(value)?;
                sim.reserve();
            }
            ("w_ba" | "w_sdd" | "w_tdd", Some(sim)) => sim.set_weights(weights),
            _ => {}
        }
        if let Some(model) = self.state.engine.exchange_mut() {
            match var.name {
                "x_g" => model.set_road_input(value)?,
                "g" => model.set_gain(value)?,
                "w_ba" | "w_sdd" | "w_tdd" => model.set_weights(weights),
                _ => {}
            }
        }
        Ok(())
    }

    /// `SetReal`. All values are checked first; a refused value leaves
    /// every variable unchanged. Tuning `g` to a new, unstable value
    /// while simulating gives `Warning` (setting the value it has changes
    /// nothing and checks nothing). Nothing is allocated but for a new
    /// `g`: the checks look each variable up again instead of collecting
    /// them.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<Status, FmiError> {
        let mut tunes = false;
        for (&vr, &value) in vrs.iter().zip(values) {
            let var = self.variable(vr, VarType::Real)?;
            self.check_settable(var, value)?;
            tunes |= var.causality == Causality::Parameter;
        }
        // Only a tuned parameter can change the rates (inputs cannot).
        if tunes && self.state.phase.is_simulating() {
            let mut candidate = self.state.settings;
            for (&vr, &value) in vrs.iter().zip(values) {
                if let Access::Real { set, .. } = self.variable(vr, VarType::Real)?.access {
                    set(&mut candidate, value);
                }
            }
            guards::check_rates(&candidate)?;
        }
        let mut gain_tuned = false;
        // The inputs that prescribe coordinates set here, a bit each.
        let mut moved = 0u32;
        for (&vr, &value) in vrs.iter().zip(values) {
            let var = self.variable(vr, VarType::Real)?;
            gain_tuned |= var.name == "g" && self.state.settings.params.g != value;
            if let Some((input, _)) = prescribed_by_name(var.name) {
                moved |= 1 << input;
            }
            self.apply_real(var, value)?;
        }
        if moved != 0 {
            self.prescribed_set(moved)?;
        }
        if gain_tuned && self.state.phase.is_simulating() {
            return Ok(self.stability_check(self.call(self.dialect.set_float)));
        }
        Ok(Status::Ok)
    }

    /// The inputs in `moved` (a bit per index into
    /// [`tdvass::model::inputs::PRESCRIBED`]; the corner's body attachment)
    /// reach the running simulation at once (`body_force` depends on them
    /// directly), both values of each together.
    fn prescribed_set(&mut self, moved: u32) -> Result<(), FmiError> {
        if moved & (1 << BODY_ATTACHMENT) != 0 {
            self.body_input_set();
        }
        let values = self.state.settings.prescribed();
        for (input, values) in values.into_iter().enumerate() {
            let Some(values) = values.filter(|_| moved & (1 << input) != 0) else {
                continue;
            };
            if let Some(sim) = self.state.engine.simulator_mut() {
                sim.set_prescribed(input, values)?;
            }
            if let Some(model) = self.state.engine.exchange_mut() {
                model.set_prescribed(input, values)?;
            }
        }
        Ok(())
    }

    /// `SetInteger` (all Integer variables are fixed parameters).
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<Status, FmiError> {
        let mut checked = Vec::with_capacity(vrs.len());
        for (&vr, &value) in vrs.iter().zip(values) {
            let var = self.variable(vr, VarType::Integer)?;
            self.check_settable(var, value as f64)?;
            checked.push((var, value));
        }
        for (var, value) in checked {
            if let Access::Integer { set, .. } = var.access {
                set(&mut self.state.settings, value);
            }
        }
        Ok(Status::Ok)
    }

    /// `SetBoolean`: the only Boolean is a calculated parameter.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Result<Status, FmiError> {
        for (&vr, &value) in vrs.iter().zip(values) {
            let var = self.variable(vr, VarType::Boolean)?;
            self.check_settable(var, value as i32 as f64)?;
        }
        Ok(Status::Ok)
    }

    /// `SetString`: there are no String variables.
    pub fn set_string(&mut self, vrs: &[u32]) -> Result<Status, FmiError> {
        self.get_string(vrs)
    }
}
