// The iteration scrubber: move the slider, and both worlds, the numbers and the "what to notice"
// lines show the policy as it was at that training iteration (the spawn pose's ghost included).
// Every frame was drawn at build time (chapter_site/landing.py); this only swaps attributes and
// text. Without JavaScript the page shows the last iteration.
(function () {
  "use strict";
  function init() {
    var data = document.getElementById("scrubber-data");
    var control = document.querySelector("#scrubber .scrub-control");
    if (!data || !control) { return; }
    var frames = JSON.parse(data.textContent);
    var slider = document.getElementById("scrub");
    var worlds = { dream: document.querySelector('#scrubber svg[data-world="in the dream"]'),
                   real: document.querySelector('#scrubber svg[data-world="in reality"]') };
    function draw(i) {
      var f = frames[i];
      Object.keys(worlds).forEach(function (w) {
        var svg = worlds[w], p = f[w];
        svg.querySelector(".tee0").setAttribute("points", p.tee[0]);
        svg.querySelector(".tee1").setAttribute("points", p.tee[1]);
        svg.querySelector(".ghost0").setAttribute("points", p.ghost[0]);
        svg.querySelector(".ghost1").setAttribute("points", p.ghost[1]);
        svg.querySelector(".block-path").setAttribute("points", p.block_path);
        svg.querySelector(".pusher-path").setAttribute("points", p.pusher_path);
        var xy = p.pusher.split(",");
        var dot = svg.querySelector(".pusher");
        dot.setAttribute("cx", xy[0]);
        dot.setAttribute("cy", xy[1]);
      });
      Object.keys(f.readout).forEach(function (k) {
        var el = document.querySelector('#scrubber [data-field="' + k + '"]');
        if (el) { el.textContent = f.readout[k]; }
      });
      slider.setAttribute("aria-valuetext", "iteration " + f.readout.iteration);
    }
    control.hidden = false;
    slider.addEventListener("input", function () { draw(Number(slider.value)); });
  }
  if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", init);
  } else {
    init();
  }
})();
