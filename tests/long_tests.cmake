# Tests left to the release run (label <label>-long; scripts/test.sh leaves them out of the
# sanitizer runs). Each takes 6 s or more in release (or 20 s or more under ASan), and runs
# code that a shorter test runs under the sanitizers too: they judge accuracy, equality or
# budgets on more frames (real sequences, rooms, laps), not other code. A name that matches no
# test fails the configuration (cmake/test_programs.cmake), so a renamed test is not left here.
# Times: release, 2 cores, unloaded (2026-11-28); under ThreadSanitizer from a loaded run.
set(RGBDMAP_LONG_TESTS
  # Accuracy of tracking (20 s, 16 s; the loop thread's test, PipelineLoopThread, 33 s, stays:
  # it is the one that runs loops, passes and checkpoints together under ThreadSanitizer)
  Odometry.TracksASyntheticRoomToMillimetres
  PipelineTracking.OdometryMapOfASyntheticRoomIsCloseToTheExactPoseMap
  # Frame-to-frame tracking on rendered rooms and 100 real frames (7 s each; 30-40 s under ASan;
  # Tracking.Fr1XyzEveryFrame, the jump, blank and frozen frames stay)
  Tracking.SyntheticFastPan
  Tracking.SyntheticDeepRoom
  Tracking.Fr1RpyHead100EveryFrame
  # The rolling shutter's accuracy (5, 2.5 and 4 s; 36, 20 and 23 s under ASan;
  # Tracking.TrackingMeasuresARollingShuttersReadout, the same code measuring the readout, stays)
  Tracking.ARollingShutterIsUndoneOnFastTurns
  Tracking.ASyntheticRollingShutterIsUndoneWithItsReadout
  Tracking.AReadoutSetOnAGlobalShutterIsMeasuredAway
  # An unregistered walk rendered and mapped three times (30 s; the registration itself stays)
  DepthRegistration.AnUnregisteredWalkMapsAsWellAsARegisteredOneWithItsKeys
  # An unregistered orbit rendered and calibrated through the command line (13 s; the
  # calibrator on rendered captures stays)
  ColorDepthCalibrator.CalibrateFindsTheKeysOfAnUnregisteredSequence
  ColorDepthCalibrator.CalibrateWithoutDepthKeysFindsTheDepthCamerasFocalLength
  # Real sequences end to end, and runs repeated to compare them (95-160 s under ThreadSanitizer;
  # PipelineReplay.Fr1XyzEndToEnd stays)
  PipelineReplay.Fr1RpyHead100EndToEnd
  PipelineReplay.KeyframeEveryFrameAndFineVoxels
  PipelineReplay.TwoReplaysGiveIdenticalMaps
  PipelineTracking.TwoOdometryReplaysGiveIdenticalMapsAndTrajectories
  # Two lossless replays with loops compared (the loop thread's own test runs the same code
  # under ThreadSanitizer)
  PipelineLoopThread.TwoLosslessReplaysWithLoopsGiveTheSameMap
  OpenNI2Cli.ATumFolderThroughTheDriverGivesTheSameMapAsReadDirectly
  OpenNI2Cli.RecordFromATumFolderWritesTheSameImages
  # Sessions continued, localised, merged and streamed on real frames (12-30 s; 140-380 s under
  # ThreadSanitizer; their refusals and the stream's pieces and merger stay)
  Continuation.ASavedMapNeverRecognisedLeavesTheRunsOwnMap
  Continuation.RealFramesOfAnotherSequenceJoinTheSavedDesksMap
  Localisation.ASavedMapNeverRecognisedIsSaidAndFails
  Localisation.RealFramesOfAnotherSequenceArePosedInTheSavedDesksFrame
  SessionStream.StaysWithinItsByteBudget
  SessionStream.ARestartedStreamAddsNothingTwiceAndANewRunReplacesTheOld
  SessionMerge.TwoSequencesOfOneDeskJoinAndASyntheticRoomIsLeftOut
  SessionFile.ItsKeyframesFusedAgainGiveTheMapTheRunWrote
  FleetMerger.AMergerRestartedFromItsSavedSessionPicksUpAgain
  FleetMerger.ARobotOnAMappedRouteIsPlacedWhereItIs
  KeptKeyframes.LapsOfTheRoomHoldAfterTheSixthWhatTheyHeldAfterTheSecond
  # The floor of fr1/rpy's odometry map against its accelerometer (3.8 s; 46 s under ASan beside
  # two others): the floor finder and the accelerometer's up run there on the synthetic room
  # (OccupancyGrid.DrawsTheSyntheticRoomsFloorPlan)
  GroundFrame.FloorOfARealMapAgreesWithTheAccelerometer
  # The incidence rule's control, the same integration with the rule off (41 s under ASan; the
  # rule's own test stays)
  FreeSpace.DistancesAlongTheRayErodeTheGrazedFloor
)
