//! What the instantiation function of every FMI version (`fmi2Instantiate`,
//! `fmi3InstantiateCoSimulation`) checks and logs alike, written once: the
//! instance name, the token of the model description (GUID or
//! instantiation token), every refusal logged through the master's logger,
//! the new slave and the line that reports it. A front-end calls these in
//! the order of its own checks and adds those only its version has (FMI
//! 2.0's `fmuType`, FMI 3.0's `eventModeUsed` and intermediate variables,
//! how each passes its resources).

use crate::Slave;
use crate::defaults::Model;
use crate::error::Status;
use crate::slave::{Dialect, LogSink, Logger};
use crate::variables::{build_lookup, model_of_token, token};
use std::path::Path;

/// One call of the instantiation function, before the instance exists.
pub struct Instantiation {
    dialect: Dialect,
    logger: LogSink,
}

impl Instantiation {
    /// An instantiation by the front-end that speaks `dialect`, logging
    /// through the master's `logger`.
    pub fn new(dialect: Dialect, logger: LogSink) -> Instantiation {
        Instantiation { dialect, logger }
    }

    /// Logs `message` as the refusal of the instantiation (an `Error`,
    /// prefixed with the function name) and gives no instance.
    pub fn refuse<T>(&self, message: &str) -> Option<T> {
        (self.logger)(
            Status::Error,
            "logStatusError",
            &format!("{}: {message}", self.function()),
        );
        None
    }

    /// `instanceName`, refused when NULL or empty.
    pub fn instance_name(&self, name: Option<&str>) -> Option<String> {
        match name {
            None => self.refuse("instanceName is NULL"),
            Some("") => self.refuse("instanceName is empty"),
            Some(name) => Some(name.to_string()),
        }
    }

    /// The model whose token the master passed, refused when NULL or the
    /// token of no model of this library (the model description and the
    /// binary are then from different builds).
    pub fn model(&self, given: Option<&str>) -> Option<Model> {
        let d = &self.dialect;
        let given = match given {
            None => return self.refuse(&format!("{} is NULL", d.token_argument)),
            Some(given) => given,
        };
        if let Some(model) = model_of_token(d.version, given) {
            return Some(model);
        }
        let known: Vec<String> = Model::ALL
            .iter()
            .map(|&m| format!("{} ({})", token(m, d.version), m.name()))
            .collect();
        self.refuse(&format!(
            "{} {given} does not match this FMU's {} {}, the models this binary serves (modelDescription.xml and binary are from different builds)",
            d.given_token,
            d.own_token,
            known.join(" or ")
        ))
    }

    /// Refuses a Model Exchange instance of a model that offers
    /// Co-Simulation only.
    pub fn interface(&self, model: Model, model_exchange: bool) -> Option<()> {
        if model_exchange && !model.offers_model_exchange() {
            return self.refuse(&format!(
                "the {} model offers Co-Simulation only: its model description declares no Model Exchange",
                model.name()
            ));
        }
        Some(())
    }

    /// The slave of the instance `name` of `model`, which checks the
    /// model's token in FMU states
    /// and logs events when `logging_on`; logs the instantiation with its
    /// resources and the front-end's `details` (appended as they are).
    pub fn slave(
        self,
        name: &str,
        model: Model,
        logging_on: bool,
        resource_path: Option<&Path>,
        details: &str,
    ) -> Slave {
        let token = token(model, self.dialect.version);
        // A model whose first variable access comes after Exit
        // Initialization Mode (the chassis's, with every parameter at its
        // default) allocates nothing for it then.
        build_lookup(model, self.dialect.version);
        let resources = resource_path
            .map(|p| format!("at {}", p.display()))
            .unwrap_or_else(|| "not given".into());
        let message = format!(
            "{}: instance `{name}` of {} ({} {token}), resources {resources}{details}",
            self.function(),
            model.name(),
            self.dialect.own_token
        );
        let slave = Slave::new(
            self.dialect,
            model,
            token,
            Logger::new(self.logger, logging_on),
        );
        slave.logger().log(Status::Ok, &message);
        slave
    }

    /// The C name of the instantiation function.
    fn function(&self) -> String {
        format!("{}{}", self.dialect.prefix, self.dialect.instantiate)
    }
}

impl Slave {
    /// Logs that the instance `name` is freed (the front-end's `Drop`).
    pub fn log_freed(&self, name: &str) {
        self.logger().log(
            Status::Ok,
            &format!(
                "{}: `{name}` freed with {} FMU state(s)",
                self.call("FreeInstance"),
                self.fmu_state_count()
            ),
        );
    }
}
