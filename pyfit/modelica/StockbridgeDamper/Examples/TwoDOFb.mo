within StockbridgeDamper.Examples;
model TwoDOFb "Two-DOF system, configuration (b) Bouc-Wen between mass 1 and mass 2 (acts on y2 - y1, equal and opposite forces)"
  extends TwoDOFBase;
equation
  connect(boucWen.flange_a, mass1.flange);
  connect(boucWen.flange_b, mass2.flange);
  annotation(experiment(StartTime=0, StopTime=120, Interval=1e-3, Tolerance=1e-8));
end TwoDOFb;
