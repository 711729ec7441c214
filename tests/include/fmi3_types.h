/*
 * The few FMI 3.0 types and function signatures that the C harnesses of
 * the tests use, declared as in fmi3PlatformTypes.h / fmi3FunctionTypes.h
 * of the standard (no FMI headers needed). fmi3Boolean is C `bool`.
 */
#ifndef TDVASS_TESTS_FMI3_TYPES_H
#define TDVASS_TESTS_FMI3_TYPES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef void *fmi3Instance;
typedef void *fmi3InstanceEnvironment;
typedef void *fmi3FMUState;
typedef uint32_t fmi3ValueReference;
typedef double fmi3Float64;
typedef int32_t fmi3Int32;
typedef int64_t fmi3Int64;
typedef bool fmi3Boolean;
typedef uint8_t fmi3Byte;
typedef const char *fmi3String;
typedef int fmi3Status;
enum { fmi3OK, fmi3Warning, fmi3Discard, fmi3Error, fmi3Fatal };

typedef void (*fmi3LogMessageCallback)(fmi3InstanceEnvironment, fmi3Status, fmi3String category,
                                       fmi3String message);
typedef void (*fmi3IntermediateUpdateCallback)(
    fmi3InstanceEnvironment, fmi3Float64 intermediateUpdateTime,
    fmi3Boolean intermediateVariableSetRequested, fmi3Boolean intermediateVariableGetAllowed,
    fmi3Boolean intermediateStepFinished, fmi3Boolean canReturnEarly,
    fmi3Boolean *earlyReturnRequested, fmi3Float64 *earlyReturnTime);

typedef fmi3Instance (*fmi3InstantiateCoSimulationTYPE)(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate);
typedef void (*fmi3FreeInstanceTYPE)(fmi3Instance);
typedef fmi3Status (*fmi3EnterInitializationModeTYPE)(fmi3Instance, fmi3Boolean toleranceDefined,
                                                      fmi3Float64 tolerance, fmi3Float64 startTime,
                                                      fmi3Boolean stopTimeDefined,
                                                      fmi3Float64 stopTime);
typedef fmi3Status (*fmi3ExitInitializationModeTYPE)(fmi3Instance);
typedef fmi3Status (*fmi3TerminateTYPE)(fmi3Instance);
typedef fmi3Status (*fmi3GetFloat64TYPE)(fmi3Instance, const fmi3ValueReference[], size_t,
                                         fmi3Float64[], size_t nValues);
typedef fmi3Status (*fmi3SetFloat64TYPE)(fmi3Instance, const fmi3ValueReference[], size_t,
                                         const fmi3Float64[], size_t nValues);
typedef fmi3Status (*fmi3SetInt32TYPE)(fmi3Instance, const fmi3ValueReference[], size_t,
                                       const fmi3Int32[], size_t nValues);
typedef fmi3Status (*fmi3SetInt64TYPE)(fmi3Instance, const fmi3ValueReference[], size_t,
                                       const fmi3Int64[], size_t nValues);
typedef fmi3Status (*fmi3GetFMUStateTYPE)(fmi3Instance, fmi3FMUState *);
typedef fmi3Status (*fmi3SetFMUStateTYPE)(fmi3Instance, fmi3FMUState);
typedef fmi3Status (*fmi3FreeFMUStateTYPE)(fmi3Instance, fmi3FMUState *);
typedef fmi3Status (*fmi3SerializedFMUStateSizeTYPE)(fmi3Instance, fmi3FMUState, size_t *);
typedef fmi3Status (*fmi3SerializeFMUStateTYPE)(fmi3Instance, fmi3FMUState, fmi3Byte[], size_t);
typedef fmi3Status (*fmi3DeserializeFMUStateTYPE)(fmi3Instance, const fmi3Byte[], size_t,
                                                  fmi3FMUState *);
typedef fmi3Status (*fmi3DoStepTYPE)(fmi3Instance, fmi3Float64 currentCommunicationPoint,
                                     fmi3Float64 communicationStepSize,
                                     fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                     fmi3Boolean *eventHandlingNeeded,
                                     fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                                     fmi3Float64 *lastSuccessfulTime);

#endif
