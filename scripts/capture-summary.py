#!/usr/bin/python3
"""What a lamina capture (`render`/`bench --capture FILE.rdc`) holds, read by RenderDoc's own
Python module (Debian: python3-renderdoc, for the system's /usr/bin/python3): the frame's
labelled regions, each draw or dispatch with its pipeline's name (lamina names every pipeline
after its entry point and variant), and the shaded draw's fragment shader: entry point and
how many specialization constants it has.

    scripts/capture-summary.py out/frame.rdc
    scripts/capture-summary.py out/frame.rdc --expect-pipeline "forward model=tm2,..."

With --expect-pipeline the exit status says whether the region labelled `shaded` holds a draw
bound to that pipeline with a fragment shader that has specialization constants (0: yes,
1: no, 2: the capture did not open or replay).
"""

import argparse
import sys

import renderdoc as rd


def actions_of(actions, structured, depth=0):
    """Every action, depth first, with its depth and name."""
    for action in actions:
        yield depth, action, action.GetName(structured)
        yield from actions_of(action.children, structured, depth + 1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("capture", help="a .rdc file written by --capture")
    parser.add_argument(
        "--expect-pipeline",
        metavar="NAME",
        help="exit 1 unless the `shaded` region draws with the pipeline of this name",
    )
    args = parser.parse_args()

    rd.InitialiseReplay(rd.GlobalEnvironment(), [])
    capture = rd.OpenCaptureFile()
    try:
        status = capture.OpenFile(args.capture, "", None)
        if status != rd.ResultCode.Succeeded:
            print(f"{args.capture}: RenderDoc could not open it: {status}", file=sys.stderr)
            return 2
        status, controller = capture.OpenCapture(rd.ReplayOptions(), None)
        if status != rd.ResultCode.Succeeded:
            print(f"{args.capture}: RenderDoc could not replay it: {status}", file=sys.stderr)
            return 2
        try:
            return summarise(controller, args)
        finally:
            controller.Shutdown()
    finally:
        capture.Shutdown()
        rd.ShutdownReplay()


def bound_at(controller, action, names):
    """The pipeline's name bound at `action`, and for a draw its fragment shader's entry point
    and specialization ids, copied out so that nothing of the replay's state outlives its
    event (RenderDoc's pipeline state lives in the replay)."""
    controller.SetFrameEvent(action.eventId, True)
    state = controller.GetVulkanPipelineState()
    if action.flags & rd.ActionFlags.Dispatch:
        return names.get(state.compute.pipelineResourceId, "?"), None
    pipeline = names.get(state.graphics.pipelineResourceId, "?")
    shader = state.fragmentShader
    return pipeline, (str(shader.entryPoint), [int(i) for i in shader.specializationIds])


def summarise(controller, args):
    structured = controller.GetStructuredFile()
    names = {r.resourceId: r.name for r in controller.GetResources()}
    work = rd.ActionFlags.Drawcall | rd.ActionFlags.Dispatch
    region = None
    found = False
    print(f"capture: {args.capture}")
    for depth, action, name in actions_of(controller.GetRootActions(), structured):
        if depth == 0:
            region = name
        if not action.flags & work:
            if action.children:
                print(f"{'  ' * depth}{name}")
            continue
        pipeline, fragment = bound_at(controller, action, names)
        print(f"{'  ' * depth}{name} (event {action.eventId}): pipeline `{pipeline}`")
        if fragment is not None:
            entry, constants = fragment
            print(
                f"{'  ' * (depth + 1)}fragment shader `{entry}`, "
                f"{len(constants)} specialization constants"
            )
            if region == "shaded" and pipeline == args.expect_pipeline and constants:
                found = True
    if args.expect_pipeline is None:
        return 0
    if not found:
        print(
            f"{args.capture}: no draw in the `shaded` region with pipeline "
            f"`{args.expect_pipeline}` and specialization constants",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
