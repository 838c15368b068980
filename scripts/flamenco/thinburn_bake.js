// Flamenco 3 job type: bake the ThinBurn sheets of a .blend on a worker, headless.
//
// Install: copy this file into the Manager's `scripts/` folder (next to flamenco-manager)
// and restart the Manager; "ThinBurn Bake" then appears in the job types of the Blender
// add-on's Flamenco panel. Workers need Blender with the ThinBurn add-on installed and
// enabled (docs/blender.md), or pass `--addons thinburn_addon` in `blenderArgs` for a legacy
// install. See docs/farm.md.
//
// One task per sheet, chained one after the other: each task opens the .blend, bakes one
// sheet with the add-on's own bake job, and saves the .blend, so the next task starts from
// the saved file (tasks that saved the same .blend at once would overwrite each other's
// modifiers). A task that fails exits non-zero with the error's text in its log and keeps
// that sheet's previous bake.

const JOB_TYPE = {
    label: "ThinBurn Bake",
    description: "Bake burning sheets (ThinBurn) without the UI and save the .blend",
    settings: [
        {
            key: "sheets",
            type: "string",
            required: true,
            eval: "','.join(o.name for o in C.scene.objects if o.type == 'MESH' and o.thinburn.enabled)",
            evalInfo: { showLinkButton: true, description: "Every ThinBurn sheet of the scene" },
            description: "Comma-separated names of the sheets to bake",
        },
        {
            key: "addon_module",
            type: "string",
            default: "bl_ext.user_default.thinburn",
            description: "The add-on's Python module: bl_ext.<repository>.thinburn for an " +
                "extension, or the folder name of a legacy add-on (thinburn_addon)",
            visible: "submission",
        },
        {
            key: "usd_dir",
            type: "string",
            subtype: "dir_path",
            default: "",
            description: "Optional: also export each baked sheet to <folder>/<name>.usda",
            visible: "submission",
        },
        // Filled in by the Flamenco add-on at submission time.
        { key: "blendfile", type: "string", required: true, visible: "web",
          description: "Path of the .blend file to bake" },
    ],
};

function compileJob(job) {
    const settings = job.settings;
    const sheets = settings.sheets.split(",").map((s) => s.trim()).filter((s) => s.length > 0);
    if (sheets.length == 0) {
        throw "ThinBurn Bake: no sheets to bake (enable ThinBurn on a mesh)";
    }
    const expr = `import ${settings.addon_module}.headless as h; h.main()`;
    let previous = null;
    for (const sheet of sheets) {
        const task = author.Task(`thinburn-bake-${sheet}`, "blender");
        let args = ["--python-expr", expr, "--", "--object", sheet];
        if (settings.usd_dir) {
            args = args.concat(["--usd", settings.usd_dir]);
        }
        task.addCommand(author.Command("blender-render", {
            exe: "{blender}",
            exeArgs: "{blenderArgs}",   // "-b -y" by default: background, auto-run scripts
            argsBefore: [],
            blendfile: settings.blendfile,
            args: args,
        }));
        if (previous !== null) {
            task.addDependency(previous);
        }
        job.addTask(task);
        previous = task;
    }
}
