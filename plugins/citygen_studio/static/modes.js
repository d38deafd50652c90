// Syntax highlighting of the citygen ruleset languages for CodeMirror 5 (simple modes): comments, strings,
// numbers and sizes, each language's keywords, rule arrows and symbols (capitalised names).
(function () {
  "use strict";
  const common = ["label", "material", "depth", "asset", "size", "case", "else", "true", "false", "none", "and", "not",
    "entrance", "street", "courtyard", "width", "height", "face_width", "face_height", "floor", "floor_count", "levels"];
  const keywords = {
    "citygen-grammar": ["split", "repeat", "repeatABA", "symsplit", "grid", "floors", "terminal", "rows", "cols"],
    "citygen-layers": ["canvas", "tolerance", "symbol", "layer", "pattern", "counter", "shape", "floors", "opaque",
      "transparent", "mask", "attached", "unoccludable", "visible", "xgroup", "ygroup", "prealign"],
    "citygen-relayout": ["model", "layout", "freq", "seq", "repeat", "shuffle", "replicate", "instances", "symmetric",
      "mirror", "align", "samesize", "budget", "within"],
    "citygen-safe": ["safe", "layout", "grid", "active", "across", "rows", "cols", "axis", "budget", "symmetry"],
  };
  for (const [name, words] of Object.entries(keywords)) {
    const word = new RegExp("(?:" + words.concat(common).join("|") + ")\\b");
    CodeMirror.defineSimpleMode(name, {
      start: [
        {regex: /#.*/, token: "comment"},
        {regex: /@\w+/, token: "meta"},
        {regex: /"(?:[^\\"]|\\.)*"?/, token: "string"},
        {regex: /-->|->|=>|\||\{|\}/, token: "operator"},
        {regex: /[~']?-?\d+(?:\.\d+)?%?/, token: "number"},
        {regex: word, token: "keyword"},
        {regex: /[A-Z][\w]*/, token: "variable-2"},
        {regex: /[a-z_][\w]*(?=\s*[:=])/, token: "attribute"},
        {regex: /[a-z_][\w]*/, token: "variable"},
      ],
      meta: {lineComment: "#"},
    });
  }
})();
