package rover.spy;

import java.awt.Component;
import java.awt.Container;
import java.awt.Frame;
import java.awt.Rectangle;
import java.awt.Robot;
import java.awt.Toolkit;
import java.awt.image.BufferedImage;
import java.io.File;
import java.lang.reflect.Array;
import java.lang.reflect.Field;
import java.lang.reflect.Method;
import java.util.ArrayList;
import java.util.HashSet;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;
import java.util.Set;
import javax.imageio.ImageIO;
import javax.swing.JFrame;
import javax.swing.JTable;
import javax.swing.SwingUtilities;
import javax.swing.table.TableModel;

/**
 * For tools/spy/test/spy_test.sh, started by tools/spy/spy.sh (ROVER_SPY_MAIN) in place of
 * lcm.spy.Spy: starts lcm-spy itself (lcm.spy.Spy.main with the arguments ./rover spy gives
 * it), then watches lcm-spy's own channel table until every expected channel shows its type,
 * at least ROVER_SPY_PROBE_MIN messages and none undecodable, and the last message lcm-spy
 * decoded on a channel has the expected field values. Then it opens lcm-spy's structure
 * viewer on the first channel and saves a screenshot of the whole X screen.
 *
 * Environment:
 *   ROVER_SPY_PROBE_EXPECT     CHANNEL=TYPE,... (TYPE "??" = must be listed as unknown)
 *   ROVER_SPY_PROBE_FIELDS     CHANNEL.field=value;... (arrays as [a, b, c])
 *   ROVER_SPY_PROBE_MIN        messages per channel (default 5)
 *   ROVER_SPY_PROBE_TIMEOUT_S  seconds to wait (default 30)
 *   ROVER_SPY_PROBE_SCREENSHOT PNG file to write
 * Exit 0 when everything was seen, 1 when not (the table and what is missing are printed),
 * 2 for bad settings.
 */
public final class SpyProbe {
  private static final class Row {
    String type = "";
    long count;
    long undecodable;
  }

  public static void main(String[] args) throws Exception {
    Map<String, String> expect = parsePairs(env("ROVER_SPY_PROBE_EXPECT", ""), ",", "=");
    Map<String, String> fields = parsePairs(env("ROVER_SPY_PROBE_FIELDS", ""), ";", "=");
    if (expect.isEmpty()) usage("ROVER_SPY_PROBE_EXPECT is empty (expected CHANNEL=TYPE,...)");
    long min = parseLong("ROVER_SPY_PROBE_MIN", env("ROVER_SPY_PROBE_MIN", "5"));
    long timeoutS = parseLong("ROVER_SPY_PROBE_TIMEOUT_S", env("ROVER_SPY_PROBE_TIMEOUT_S", "30"));
    String screenshot = env("ROVER_SPY_PROBE_SCREENSHOT", "");

    long t0 = System.nanoTime();
    lcm.spy.Spy.main(args);  // lcm-spy's own entry point: its window, its LCM subscription
    System.out.println("spy probe: lcm-spy started in " + ms(t0) + " ms; waiting up to " + timeoutS + " s");

    long deadline = System.nanoTime() + timeoutS * 1_000_000_000L;
    JTable table = null;
    List<String> missing = List.of("lcm-spy's window");
    Map<String, Row> rows = Map.of();
    while (System.nanoTime() < deadline) {
      if (table == null) table = findSpyTable();
      if (table != null) {
        rows = readTable(table);
        missing = check(rows, expect, min);
        if (missing.isEmpty()) missing = checkFields(spyOf(table), fields);
        if (missing.isEmpty()) break;
      }
      Thread.sleep(200);
    }
    printTable(rows);
    if (!missing.isEmpty()) {
      System.out.println("spy probe: FAIL after " + timeoutS + " s: " + String.join("; ", missing));
      System.exit(1);
    }
    System.out.println("spy probe: every expected channel decoded after " + ms(t0) + " ms: " + expect);
    if (!fields.isEmpty()) System.out.println("spy probe: decoded fields as published: " + fields);
    if (!screenshot.isEmpty()) {
      String first = expect.keySet().iterator().next();
      openViewer(spyOf(table), first);
      waitForRate(table, first, deadline);
      System.out.println("spy probe: structure viewer for " + first + " opened after " + ms(t0) + " ms");
      String why = saveScreenshot(new File(screenshot));
      if (why != null) {
        System.out.println("spy probe: FAIL: screenshot " + screenshot + ": " + why);
        System.exit(1);
      }
      System.out.println("spy probe: screenshot " + screenshot + " after " + ms(t0) + " ms");
    }
    System.exit(0);
  }

  private static long ms(long t0) {
    return (System.nanoTime() - t0) / 1_000_000;
  }

  private static String env(String name, String fallback) {
    String v = System.getenv(name);
    return v == null ? fallback : v;
  }

  private static void usage(String why) {
    System.err.println("spy probe: " + why);
    System.exit(2);
  }

  private static long parseLong(String name, String text) {
    try {
      long v = Long.parseLong(text.trim());
      if (v > 0) return v;
    } catch (NumberFormatException e) {
      // reported below
    }
    usage(name + " '" + text + "': expected a positive integer");
    return 0;
  }

  private static Map<String, String> parsePairs(String text, String sep, String eq) {
    Map<String, String> out = new LinkedHashMap<>();
    for (String item : text.split(sep)) {
      if (item.isBlank()) continue;
      int at = item.indexOf(eq);
      if (at <= 0) usage("'" + item + "': expected KEY" + eq + "VALUE");
      out.put(item.substring(0, at).trim(), item.substring(at + 1).trim());
    }
    return out;
  }

  /** lcm-spy's channel table, once its "LCM Spy" window is showing. */
  private static JTable findSpyTable() throws Exception {
    JTable[] found = new JTable[1];
    SwingUtilities.invokeAndWait(() -> {
      for (Frame f : Frame.getFrames()) {
        if (f.isShowing() && "LCM Spy".equals(f.getTitle())) found[0] = findTable(f);
      }
    });
    return found[0];
  }

  private static JTable findTable(Container c) {
    for (Component child : c.getComponents()) {
      if (child instanceof JTable) return (JTable) child;
      if (child instanceof Container) {
        JTable t = findTable((Container) child);
        if (t != null) return t;
      }
    }
    return null;
  }

  /** What lcm-spy shows: columns Channel, Type, Num Msgs, ..., Undecodable. */
  private static Map<String, Row> readTable(JTable table) throws Exception {
    Map<String, Row> rows = new LinkedHashMap<>();
    SwingUtilities.invokeAndWait(() -> {
      TableModel m = table.getModel();
      int undecodableCol = m.getColumnCount() - 1;
      if (!"Undecodable".equals(m.getColumnName(undecodableCol))) return;
      for (int r = 0; r < m.getRowCount(); ++r) {
        Row row = new Row();
        row.type = String.valueOf(m.getValueAt(r, 1));
        row.count = Long.parseLong(String.valueOf(m.getValueAt(r, 2)).trim());
        row.undecodable = Long.parseLong(String.valueOf(m.getValueAt(r, undecodableCol)).trim());
        rows.put(String.valueOf(m.getValueAt(r, 0)), row);
      }
    });
    return rows;
  }

  private static List<String> check(Map<String, Row> rows, Map<String, String> expect, long min) {
    List<String> missing = new ArrayList<>();
    for (Map.Entry<String, String> e : expect.entrySet()) {
      Row row = rows.get(e.getKey());
      boolean unknown = e.getValue().equals("??");
      if (row == null) {
        missing.add(e.getKey() + ": not listed");
      } else if (unknown ? !row.type.startsWith("?? ") : !row.type.equals(e.getValue())) {
        missing.add(e.getKey() + ": type '" + row.type + "', expected '" + e.getValue() + "'");
      } else if (row.count < min) {
        missing.add(e.getKey() + ": " + row.count + " messages, expected at least " + min);
      } else if (!unknown && row.undecodable != 0) {
        missing.add(e.getKey() + ": " + row.undecodable + " undecodable, expected 0");
      }
    }
    return missing;
  }

  private static void printTable(Map<String, Row> rows) {
    System.out.println("spy probe: lcm-spy's table (channel, type, messages, undecodable):");
    for (Map.Entry<String, Row> e : rows.entrySet()) {
      Row r = e.getValue();
      System.out.printf("  %-20s %-24s %6d %4d%n", e.getKey(), r.type, r.count, r.undecodable);
    }
  }

  // lcm-spy keeps its Spy object only behind its table model (LCM 1.3.1's lcm.spy.Spy:
  // TableSorter -> Spy$ChannelTableModel -> Spy, whose channelMap holds each channel's last
  // decoded message in ChannelData.last).
  private static Object spyOf(JTable table) throws Exception {
    Object model = ((lcm.util.TableSorter) table.getModel()).getTableModel();
    return field(model, "this$0");
  }

  private static Object field(Object o, String name) throws Exception {
    Field f = o.getClass().getDeclaredField(name);
    f.setAccessible(true);
    return f.get(o);
  }

  private static lcm.spy.ChannelData channel(Object spy, String channel) throws Exception {
    Object list = field(spy, "channelList");
    synchronized (list) {
      @SuppressWarnings("unchecked")
      Map<String, lcm.spy.ChannelData> map = (Map<String, lcm.spy.ChannelData>) field(spy, "channelMap");
      return map.get(channel);
    }
  }

  private static String show(Object v) {
    if (v == null || !v.getClass().isArray()) return String.valueOf(v);
    StringBuilder s = new StringBuilder("[");
    for (int i = 0; i < Array.getLength(v); ++i) s.append(i == 0 ? "" : ", ").append(show(Array.get(v, i)));
    return s.append("]").toString();
  }

  private static List<String> checkFields(Object spy, Map<String, String> fields) throws Exception {
    List<String> missing = new ArrayList<>();
    for (Map.Entry<String, String> e : fields.entrySet()) {
      int dot = e.getKey().indexOf('.');
      if (dot <= 0) usage("'" + e.getKey() + "': expected CHANNEL.field");
      String ch = e.getKey().substring(0, dot);
      String name = e.getKey().substring(dot + 1);
      lcm.spy.ChannelData cd = channel(spy, ch);
      Object last = cd == null ? null : cd.last;
      if (last == null) {
        missing.add(ch + ": no decoded message yet");
        continue;
      }
      String got;
      try {
        got = show(last.getClass().getField(name).get(last));
      } catch (NoSuchFieldException ex) {
        missing.add(ch + ": " + last.getClass().getName() + " has no field " + name);
        continue;
      }
      if (!got.equals(e.getValue())) missing.add(e.getKey() + " = " + got + ", expected " + e.getValue());
    }
    return missing;
  }

  /** lcm-spy's structure viewer for a channel (what a double-click opens), below its table. */
  private static void openViewer(Object spy, String channel) throws Exception {
    lcm.spy.ChannelData cd = channel(spy, channel);
    Method create = spy.getClass().getDeclaredMethod("createViewer", lcm.spy.ChannelData.class);
    create.setAccessible(true);
    Exception[] failed = new Exception[1];
    SwingUtilities.invokeAndWait(() -> {
      try {
        create.invoke(spy, cd);
        JFrame viewer = cd.viewerFrame;
        viewer.setLocation(0, 610);
        viewer.toFront();
      } catch (Exception ex) {
        failed[0] = ex;
      }
    });
    if (failed[0] != null) throw failed[0];
  }

  /** For the picture only: until lcm-spy's once-a-second refresh has shown a rate (Hz > 0). */
  private static void waitForRate(JTable table, String channel, long deadline) throws Exception {
    long until = Math.max(deadline, System.nanoTime() + 5_000_000_000L);
    while (System.nanoTime() < until) {
      double[] hz = {0};
      SwingUtilities.invokeAndWait(() -> {
        TableModel m = table.getModel();
        for (int r = 0; r < m.getRowCount(); ++r) {
          if (channel.equals(String.valueOf(m.getValueAt(r, 0)))) {
            try {
              hz[0] = Double.parseDouble(String.valueOf(m.getValueAt(r, 3)).trim());
            } catch (NumberFormatException e) {
              hz[0] = 0;  // "NaN" before the first refresh
            }
          }
        }
      });
      if (hz[0] > 0) return;
      Thread.sleep(200);
    }
  }

  /** Null when written, else why not. A screen of one colour means nothing was drawn. */
  private static String saveScreenshot(File out) throws Exception {
    // lcm-spy repaints its viewer with each message (20 Hz here): let it paint, then let the
    // event queue drain (cheaper than Robot.waitForIdle on a busy host).
    Thread.sleep(500);
    SwingUtilities.invokeAndWait(() -> {});
    Robot robot = new Robot();
    BufferedImage img = robot.createScreenCapture(new Rectangle(Toolkit.getDefaultToolkit().getScreenSize()));
    Set<Integer> colours = new HashSet<>();
    for (int y = 0; y < img.getHeight(); y += 4) {
      for (int x = 0; x < img.getWidth(); x += 4) colours.add(img.getRGB(x, y));
    }
    if (colours.size() < 2) return "the screen is blank (one colour)";
    File dir = out.getAbsoluteFile().getParentFile();
    if (dir != null) dir.mkdirs();
    if (!ImageIO.write(img, "png", out)) return "no PNG writer";
    return null;
  }
}
