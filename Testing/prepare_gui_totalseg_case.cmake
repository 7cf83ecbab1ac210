# The GUI test's TotalSegmentator case: `repose prepare --skeleton auto` on the shared example, as a
# user prepares it. Run by CTest as a fixture with -DREPOSE=... -DDATA=... -DWORK=...; without the
# shared data it prepares nothing and the GUI test skips that part.
set(ts "${DATA}/totalsegmentator")
file(REMOVE_RECURSE "${WORK}")
if(NOT EXISTS "${ts}/example_seg_fast_force_split.nii.gz")
  message(STATUS "no shared TotalSegmentator data in ${ts}: nothing prepared")
  return()
endif()
execute_process(
  COMMAND "${REPOSE}" prepare --labels "${ts}/example_seg_fast_force_split.nii.gz" --image "${ts}/example_ct.nii.gz"
    --skeleton auto --label-table "${ts}/labels_total_v2.tsv" --mesh-spacing 6 --out "${WORK}/case"
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "repose prepare failed (${rc})")
endif()
# A case that does not keep its label table yet finds the names beside it (the GUI looks there too).
if(NOT EXISTS "${WORK}/case/labels.tsv")
  file(COPY "${ts}/labels_total_v2.tsv" DESTINATION "${WORK}")
  file(RENAME "${WORK}/labels_total_v2.tsv" "${WORK}/labels.tsv")
endif()
