use super::*;
use crate::{FMI_VERSION, Model, TYPES_PLATFORM};

#[test]
fn panics_are_caught_and_make_the_instance_fatal() {
    let guid = crate::guid(Model::QuarterCar);
    let instance = Instance::instantiate(
        InstantiateRequest {
            instance_name: Some("p"),
            fmu_type: FMI2_COSIMULATION,
            guid: Some(&guid),
            ..Default::default()
        },
        Box::new(|_, _, _| {}),
    )
    .unwrap();
    let c = into_component(instance);
    let s = call(c, Function::Reset, |_| panic!("deliberate"));
    assert_eq!(s, status(Status::Fatal));
    // SAFETY: `c` is the live handle created above.
    unsafe {
        assert_eq!(fmi2Reset(c), status(Status::Error));
        fmi2FreeInstance(c);
    }
}

#[test]
fn null_and_foreign_components_are_refused() {
    // SAFETY: NULL is a valid argument by contract.
    unsafe {
        assert_eq!(fmi2Reset(std::ptr::null_mut()), status(Status::Error));
        fmi2FreeInstance(std::ptr::null_mut());
        assert!(
            fmi2Instantiate(
                c"x".as_ptr(),
                1,
                c"{}".as_ptr(),
                std::ptr::null(),
                std::ptr::null(),
                0,
                0
            )
            .is_null()
        );
    }
    let mut not_a_handle = [0u64; 8];
    let c = not_a_handle.as_mut_ptr() as fmi2Component;
    // SAFETY: points to readable memory the size of a handle tag.
    assert_eq!(unsafe { fmi2Terminate(c) }, status(Status::Error));
}

#[test]
fn version_strings() {
    // SAFETY: static NUL-terminated strings.
    unsafe {
        assert_eq!(
            CStr::from_ptr(fmi2GetVersion()).to_str().unwrap(),
            FMI_VERSION
        );
        assert_eq!(
            CStr::from_ptr(fmi2GetTypesPlatform()).to_str().unwrap(),
            TYPES_PLATFORM
        );
    }
}
